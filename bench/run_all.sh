#!/bin/bash
# Every figure of bench/README.md, in one go: builds the bench targets in BUILD (default
# build-perf, configured as in the README), then runs the suite and writes one text file per
# part into OUT (default /tmp/fibre_bench). Takes about 20 minutes on 2 cores.
#   bench/run_all.sh [BUILD] [OUT]
# Environment: BLAS_DIR=<dir with an optimized libblas.so.3> runs MUMPS on it (the README's
# figures used Debian's libopenblas0-serial, unpacked without installing it); SYS_FILES="a.sys
# b.sys" adds exported systems (fix fibre_contact export) to the direct-vs-Krylov table;
# SKIP_E2E=1 / SKIP_MPI=1 skip the LAMMPS runs (they need build/fix/lmp_fibre).
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$src/build-perf}
out=${2:-/tmp/fibre_bench}
mkdir -p "$out"
make -C "$build" -j2 bench > "$out/make.txt" 2>&1
b=$build/bench
export OMP_NUM_THREADS=1
blas_env=()
[ -n "${BLAS_DIR:-}" ] && blas_env=(env LD_LIBRARY_PATH="$BLAS_DIR")
sys_args=()
for f in ${SYS_FILES:-}; do sys_args+=(--sys "$f"); done

"$b/bench_schur" > "$out/schur.txt" 2>&1
"$b/bench_precond" > "$out/precond.txt" 2>&1
"$src/bench/profile.sh" "$build" 15000 3 > "$out/profile.txt" 2>&1
"${blas_env[@]}" "$b/bench_direct_vs_krylov" --repeat 3 "${sys_args[@]}" > "$out/direct_vs_krylov.txt" 2>&1
if [ -z "${SKIP_MPI:-}" ]; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
  for np in 1 2; do
    mpirun --mca btl_vader_single_copy_mechanism none -np $np "$b/bench_mpi_latency"
  done > "$out/mpi_latency.txt" 2>&1
  "$src/bench/mpi_scaling.sh" --np "1 2" --N 1400 --tend 3.0 > "$out/mpi_scaling.txt" 2>&1
fi
if [ -z "${SKIP_E2E:-}" ]; then
  "$src/bench/e2e_speed.sh" --deck material --N 1400 --tend 3.0 > "$out/e2e_material.txt" 2>&1
  "$src/bench/e2e_speed.sh" --deck silo --N 1400 --tend 3.0 > "$out/e2e_silo.txt" 2>&1
  "$src/bench/e2e_speed.sh" --deck silo --N 5000 --tend 2.0 --work /tmp/fibre_e2e_s5000 > "$out/e2e_silo5000.txt" 2>&1
  "$src/bench/e2e_speed.sh" --deck material --N 5000 --tend 8.0 --work /tmp/fibre_e2e_m5000 > "$out/e2e_material5000.txt" 2>&1
fi
echo "figures in $out"
