#!/bin/bash
# Packs lmp_fibre, Debian's lmp and Open MPI's mpirun with every shared library they load
# (glibc's loader included) into one archive, for timing runs on a machine that has none of
# them (a lent 16-core machine of another distribution). Each program runs through the
# bundled loader, so nothing of the host's libraries is used; Open MPI and PMIx find their
# plugins and help files in the bundle through their MCA variables. PMIx also opens some
# plugins from its compiled-in folder (/usr/lib/<arch>/pmix2): where the host has its own
# PMIx there, hide it (bench/device_scaling.sh binds an empty folder over it).
#
# Usage: bench/bundle.sh [--lmp-fibre PATH] [--out FILE.tar.xz]
# There:  tar xf FILE.tar.xz -C DIR; PATH=DIR/bin:$PATH; mpirun -np 16 lmp_fibre -in ...
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
lmp_fibre=$src/build/fix/lmp_fibre
out=$src/.device/bundle.tar.xz
while [ $# -gt 0 ]; do
  case $1 in
    --lmp-fibre) lmp_fibre=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "bundle.sh: unknown option '$1' (expected --lmp-fibre PATH or --out FILE)" >&2; exit 1 ;;
  esac
done
arch=$(gcc -print-multiarch)
ompi_plugins=/usr/lib/$arch/openmpi/lib/openmpi3
pmix_plugins=/usr/lib/$arch/pmix2/lib/pmix
loader=$(readlink -f /lib64/ld-linux-x86-64.so.2)
for f in "$lmp_fibre" /usr/bin/lmp /usr/bin/orterun "$ompi_plugins" "$pmix_plugins" "$loader"; do
  [ -e "$f" ] || { echo "bundle.sh: $f not found" >&2; exit 1; }
done

b=$(mktemp -d)
trap 'rm -rf "$b"' EXIT
mkdir -p "$b/bin" "$b/real" "$b/so" "$b/ompi" "$b/pmix" "$b/share" "$b/hwloc"
cp "$lmp_fibre" "$b/real/lmp_fibre"
cp /usr/bin/lmp "$b/real/lmp"
cp /usr/bin/orterun "$b/real/mpirun"
strip "$b/real/"*
cp "$ompi_plugins"/*.so "$b/ompi/"
cp "$pmix_plugins"/*.so "$b/pmix/"
cp -r /usr/share/openmpi "$b/share/openmpi"
[ -d /usr/share/pmix ] && cp -r /usr/share/pmix "$b/share/pmix"

# Every library that a program or plugin needs, found by the host's loader.
for elf in "$b"/real/* "$b"/ompi/*.so "$b"/pmix/*.so; do
  ldd "$elf" 2>/dev/null | awk '$2 == "=>" && $3 ~ /^\// { print $3 }'
done | sort -u | while read -r lib; do
  cp -L "$lib" "$b/so/"
done
cp -L "$loader" "$b/so/ld-linux-x86-64.so.2"

# The libraries are in so/, not lib/: mpirun puts OPAL_PREFIX/lib on the ranks' LD_LIBRARY_PATH,
# which would hand the bundle's glibc to the host's /bin/sh.
# One wrapper per program: the bundled loader with the bundle's libraries, and the MCA
# variables that point Open MPI and PMIx at the bundle's plugins and help files (hwloc's
# optional plugins, GL, OpenCL and PCI, are left out: an empty folder).
for prog in lmp_fibre lmp mpirun; do
  cat > "$b/bin/$prog" <<EOF
#!/bin/sh
B=\$(cd "\$(dirname "\$0")/.." && pwd)
export OPAL_PREFIX="\$B" OPAL_PKGDATADIR="\$B/share/openmpi"
export OMPI_MCA_mca_base_component_path="\$B/ompi" PMIX_MCA_mca_base_component_path="\$B/pmix"
export PMIX_INSTALL_PREFIX="\$B" PMIX_PREFIX="\$B" HWLOC_PLUGINS_PATH="\$B/hwloc"
exec "\$B/so/ld-linux-x86-64.so.2" --library-path "\$B/so" "\$B/real/$prog" "\$@"
EOF
  chmod +x "$b/bin/$prog"
done

mkdir -p "$(dirname "$out")"
tar -C "$b" -cf - . | xz -T2 -6 > "$out"
echo "bundle.sh: $out, $(du -h "$out" | cut -f1) ($(du -sh "$b" | cut -f1) unpacked)"
