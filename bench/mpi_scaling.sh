#!/bin/bash
# Strong scaling of fix fibre_contact under MPI: the same deck at 1, 2, ... ranks, with the
# parallel efficiency T1 / (p Tp), the fix's own timings (f_fc[8] preconditioner setup and
# f_fc[9] linear solve, seconds per step, slowest process, averaged over every step with fix
# ave/time) and LAMMPS's MPI task timing breakdown (Pair/Neigh/Comm/Modify/Output/Other;
# the fix's contact detection, system build, preconditioner and solve are all in Modify).
#
# Usage: bench/mpi_scaling.sh [options]
#   --np "1 2"          rank counts (e.g. "1 2 4 8 16" on a larger machine)
#   --deck material     examples/<deck>/in.<deck> (material or silo)
#   --N 1400            spheres (-var N)
#   --tend 2.0          simulated seconds (material: -var tend; silo: -var tfill, no discharge)
#   --lmp PATH          lmp_fibre (default build/fix/lmp_fibre)
#   --work DIR          work directory (default /tmp/fibre_mpi_scaling)
#   --extra "KEYS"      more fix fibre_contact keywords (-var fc_extra), e.g. "precond fibre"
#   --balance K         rebalance the processes' domains every K steps (fix balance K 1.05
#                       shift xyz 10 1.05; the decks' piles fill few cells of a uniform grid)
#   --vars "K V ..."    more deck variables for both twins (-var K V), e.g. "E 1e8 seed 4767"
#   --native LMP        also run the native twin (examples/<deck>/in.<deck>.native) with this
#                       lmp at each rank count, after the fix's run, and print its loop time and
#                       native / fix (the same material, the native step scaled with E)
#   --mpirun-flags "F"  flags for mpirun (default: --mca btl_vader_single_copy_mechanism none,
#                       see below; pass "" for Open MPI's defaults)
# Open MPI's shared-memory transport copies messages above its 4 KB eager limit with a
# single-copy mechanism (CMA) that is slow in containers without ptrace rights: here a 7 KB
# halo message took 51 us with it and 3.4 us without (bench_mpi_latency), and a Krylov
# iteration makes several such exchanges. The default flag turns it off.
# The deck is copied into the work directory with its thermo columns set to the fix's timings
# (the examples themselves are not modified). Needs mpirun; as root, Open MPI wants
# OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 (set below); more ranks than
# cores needs --oversubscribe (added automatically when np > cores).
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
. "$src/bench/common.sh"
np="1 2"  # a list here
deck=material
N=1400
tend=2.0
lmp=$src/build/fix/lmp_fibre
work=/tmp/fibre_mpi_scaling
extra=""
balance=0
vars=""
native=""
mpirun_flags="--mca btl_vader_single_copy_mechanism none"
parse_options "$0" "$@"
nps=$np
enter_work "$src"
varargs=()
read -ra kv <<< "$vars"
[ $((${#kv[@]} % 2)) -eq 0 ] || { echo "mpi_scaling.sh: --vars takes pairs K V, got '$vars'" >&2; exit 2; }
for ((i = 0; i < ${#kv[@]}; i += 2)); do varargs+=(-var "${kv[i]}" "${kv[i + 1]}"); done
if [ "$balance" -gt 0 ]; then
  sed -i "s/^include  *run\.$deck/fix       fc_balance all balance $balance 1.05 shift xyz 10 1.05\n&/" "in.$deck"
fi

echo "mpi_scaling: $(date -u '+%Y-%m-%d %H:%M UTC'), $(hostname), $cores cores;" \
     "deck $deck N $N tend $tend, vars '$vars', extra '$extra', balance $balance," \
     "mpirun flags '$mpirun_flags'${native:+, native $native}"
printf '%4s %10s %8s %8s %10s %10s %10s %9s %8s %8s %8s %8s %8s\n' np loop_s speedup eff \
  setup_ms/st solve_ms/st sweep_ms/st sweeps/st pair% neigh% comm% modify% other%
# The last run with steps of a log and its timing breakdown (the silo's fill is followed by a
# run 0).
last_run() {  # log
  awk '/^Loop time of/ { keep = $9 > 0; if (keep) s = "" } keep { s = s $0 "\n" }
       END { printf "%s", s }' "$1"
}
loop_seconds() { sed -n 's/^Loop time of \([0-9.e+-]*\) on .*/\1/p' <<< "$1"; }  # last_run's text
loop_steps() { sed -n 's/.* for \([0-9]*\) steps with .*/\1/p' <<< "$1"; }
t1=""
for np in $nps; do
  over=""
  [ "$np" -gt "$cores" ] && over="--oversubscribe"
  log=log.np$np
  # shellcheck disable=SC2086
  mpirun $mpirun_flags $over -np "$np" "$lmp" -in "in.$deck" -var N "$N" $timevar "${varargs[@]}" \
    -var fc_extra "$extra" -log "$log" -screen none > "out.np$np" 2>&1 ||
    { echo "np $np failed, see $work/out.np$np"; continue; }
  last=$(last_run "$log")
  loop=$(loop_seconds "$last")
  steps=$(loop_steps "$last")
  timing=$(sed -n 's/^fibre_timing setup_per_step \([^ ]*\) solve_per_step \([^ ]*\) sweep_per_step \([^ ]*\) sweeps_per_step \([^ ]*\)/\1 \2 \3 \4/p' "$log" | tail -1)
  pct() { awk -v k="$1" '$1 == k && $2 == "|" { print $NF }' <<< "$last" | tail -1; }
  [ -z "$t1" ] && t1=$loop && p1=$np
  awk -v np="$np" -v loop="$loop" -v t1="$t1" -v p1="$p1" -v tm="$timing" \
      -v pair="$(pct Pair)" -v neigh="$(pct Neigh)" -v comm="$(pct Comm)" \
      -v modify="$(pct Modify)" -v other="$(pct Other)" 'BEGIN {
    split(tm, t, " ");
    s = t1 / loop; e = s * p1 / np;
    printf "%4d %10.2f %8.2f %7.0f%% %10.2f %10.2f %10.2f %9.1f %8s %8s %8s %8s %8s\n", np, loop, s,
      100 * e, 1e3 * t[1], 1e3 * t[2], 1e3 * t[3], t[4], pair, neigh, comm, modify, other }'
  echo "     ($steps steps; LAMMPS log $work/$log)"
  [ -n "$native" ] || continue
  # shellcheck disable=SC2086
  mpirun $mpirun_flags $over -np "$np" "$native" -in "in.$deck.native" -var N "$N" $timevar \
    "${varargs[@]}" -log "native.$log" -screen none > "out.native.np$np" 2>&1 ||
    { echo "native np $np failed, see $work/out.native.np$np"; continue; }
  last=$(last_run "native.$log")
  awk -v n="$(loop_seconds "$last")" -v f="$loop" -v ns="$(loop_steps "$last")" 'BEGIN {
    printf "     native: loop_s %.2f (%d steps), native / fix %.2f\n", n, ns, n / f }'
done
echo "eff = T(first) * np(first) / (np * T): parallel efficiency of the loop time"
