#!/bin/bash
# MPI scaling of fix fibre_contact and its native twin on a lent machine without LAMMPS or
# Debian's Open MPI (bench/README.md, "16 cores"): unpacks bench/bundle.sh's archive, hides
# the host's own Open MPI, PMIx and hwloc plugin folders in a private mount namespace (the
# bundle's PMIx would open plugins of another version there), and runs mpi_scaling.sh.
#
# Usage: bench/device_scaling.sh BUNDLE.tar.xz OUTDIR [--quick]
#   --quick   a smoke run of the same commands (N 350, 1 s, np 1 and 2)
set -u
[ $# -ge 2 ] || { echo "usage: $0 BUNDLE.tar.xz OUTDIR [--quick]" >&2; exit 2; }
bundle=$(readlink -f "$1") out=$(readlink -f "$2") quick=${3:-}
src=$(cd "$(dirname "$0")/.." && pwd)
if [ -z "${FIBRE_IN_NS:-}" ] && unshare -m --propagation private true 2>/dev/null; then
  FIBRE_IN_NS=1 exec unshare -m --propagation private bash "$0" "$@"
fi
arch=x86_64-linux-gnu
mkdir -p /tmp/fibre_empty "$out"
if [ -n "${FIBRE_IN_NS:-}" ]; then
  for d in /usr/lib/$arch/pmix2 /usr/lib/$arch/openmpi /usr/lib/$arch/hwloc; do
    [ -d "$d" ] && mount --bind /tmp/fibre_empty "$d"
  done
fi
B=/tmp/fibre_bundle
rm -rf "$B" && mkdir -p "$B" && tar xf "$bundle" -C "$B" || exit 1
export PATH=$B/bin:$PATH OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{ date -u; nproc; lscpu | head -25; head -3 /etc/os-release; echo "namespace: ${FIBRE_IN_NS:-no}"; } \
  > "$out/machine.txt" 2>&1
(cd "$src/examples/material" && timeout 60 mpirun --mca btl_vader_single_copy_mechanism none \
  -np 2 lmp_fibre -in in.material -var N 350 -var tend 1 -log none -screen none) \
  > "$out/smoke.txt" 2>&1
rc=$?; echo "smoke rc $rc" >> "$out/smoke.txt"; [ $rc -eq 0 ] || exit 1

S="bash $src/bench/mpi_scaling.sh --lmp $B/bin/lmp_fibre"
N1=1400 N2=5000 T2=10.0 T1=0 np1="1 16 4" np2="1 16 2 4 8" np3="16 8"
[ "$quick" = --quick ] && N1=350 N2=350 T2=1.0 T1=1.0 np1="1 2" np2="1 2" np3="2"
$S --np "$np1" --N $N1 --tend $T1 --vars "E 1e8 seed 4767" --native "$B/bin/lmp" \
  --work /tmp/fs_a 2>&1 | tee "$out/a_e1e8.txt"
$S --np "$np2" --N $N2 --tend $T2 --work /tmp/fs_b 2>&1 | tee "$out/b_n5000.txt"
$S --np "$np1" --N $N1 --tend $T1 --vars "E 5e6 seed 4767" --native "$B/bin/lmp" \
  --work /tmp/fs_c 2>&1 | tee "$out/c_e5e6.txt"
$S --np "$np3" --N $N2 --tend $T2 --balance 100 --work /tmp/fs_d 2>&1 | tee "$out/d_balance.txt"
date -u >> "$out/machine.txt"
tar czf "$out/logs.tgz" /tmp/fs_[abcd]/log.* /tmp/fs_[abcd]/native.log.* /tmp/fs_[abcd]/out.* \
  2>/dev/null
