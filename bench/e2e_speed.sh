#!/bin/bash
# End-to-end speed: simulated seconds per wall-clock second of fix fibre_contact against the
# native LAMMPS twin of the same scene (examples/<deck>/in.<deck>.native: Hertz/Mindlin
# granular pair style with nve/sphere, at its stable step 1/20 of the Hertz collision time;
# the fibre deck runs 25x that step). Both decks pour the same particles from the same emitter.
# Prints the ratio and where the fibre run's time goes: LAMMPS's breakdown (the fix runs
# inside Modify) and the fix's own preconditioner setup (f_fc[8]) and linear solve (f_fc[9])
# per step, averaged over every step; Modify minus those is contact detection, system build,
# active-set bookkeeping and the velocity update.
#
# Usage: bench/e2e_speed.sh [--deck material|silo] [--N 1400] [--tend 3.0] [--np 1]
#                           [--lmp build/fix/lmp_fibre] [--work DIR] [--extra "KEYS"]
#                           [--mpirun-flags "F"]
# tend: simulated seconds (material: -var tend; silo: -var tfill, no discharge).
# mpirun flags: default --mca btl_vader_single_copy_mechanism none (see mpi_scaling.sh).
# The options are those of mpi_scaling.sh (bench/common.sh parses both).
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
. "$src/bench/common.sh"
deck=material
N=1400
tend=3.0
np=1
lmp=$src/build/fix/lmp_fibre
work=/tmp/fibre_e2e_speed
extra=""
mpirun_flags="--mca btl_vader_single_copy_mechanism none"
parse_options "$0" "$@"
enter_work "$src"
flags=$mpirun_flags
[ "$np" -gt "$cores" ] && flags="$flags --oversubscribe"

echo "e2e_speed: $(date -u '+%Y-%m-%d %H:%M UTC'), $(hostname), $cores cores, np $np;" \
     "deck $deck N $N, $tend simulated s"
declare -A loop steps
for run in fibre native; do
  input=in.$deck
  [ $run = native ] && input=in.$deck.native
  # shellcheck disable=SC2086
  mpirun $flags -np "$np" "$lmp" -in "$input" -var N "$N" $timevar -var fc_extra "$extra" \
    -log "log.$run" -screen none > "out.$run" 2>&1 || { echo "$run run failed: $work/out.$run"; exit 1; }
  # Summed over the deck's runs (the silo deck runs filling, then discharge).
  loop[$run]=$(awk '/^Loop time of/ { t += $4 } END { print t }' "log.$run")
  steps[$run]=$(awk '/^Loop time of/ { n += $9 } END { print n }' "log.$run")
  atoms=$(sed -n 's/.* steps with \([0-9]*\) atoms.*/\1/p' "log.$run" | tail -1)
  awk -v r=$run -v l="${loop[$run]}" -v s="${steps[$run]}" -v t="$tend" -v a="$atoms" 'BEGIN {
    printf "  %-7s %7d steps, %6d atoms at the end, loop %9.2f s: %8.4f simulated s per wall s\n",
      r, s, a, l, t / l }'
done
awk -v f="${loop[fibre]}" -v n="${loop[native]}" 'BEGIN {
  printf "  fibre_contact / native speed: %.2fx (target >= 5x at 5000 bodies)\n", n / f }'
echo "  (LAMMPS wall-clock loop times: on a shared machine, repeat and compare ratios)"
tm=$(sed -n 's/^fibre_timing setup_per_step \([^ ]*\) solve_per_step \([^ ]*\) sweep_per_step \([^ ]*\)/\1 \2 \3/p' log.fibre | tail -1)
modify=$(awk '$1 == "Modify" && $2 == "|" { m += $5 } END { print m }' log.fibre)  # avg times, summed
awk -v tm="$tm" -v st="${steps[fibre]}" -v l="${loop[fibre]}" -v m="$modify" 'BEGIN {
  split(tm, t, " "); setup = t[1] * st; solve = t[2] * st; sweep = t[3] * st;
  printf "  fibre run, where the time goes (s, %% of loop):\n";
  printf "    preconditioner setup  %8.2f %5.1f%%\n", setup, 100 * setup / l;
  printf "    linear solves         %8.2f %5.1f%%\n", solve, 100 * solve / l;
  printf "    Gauss-Seidel sweeps   %8.2f %5.1f%%  (with the complementarity residuals)\n",
    sweep, 100 * sweep / l;
  rest = m - setup - solve - sweep;
  printf "    rest of the fix       %8.2f %5.1f%%  (detection, system build, active set, update)\n",
    rest, 100 * rest / l;
  printf "    outside the fix       %8.2f %5.1f%%  (neighbour lists, comm, output, pour)\n",
    l - m, 100 * (l - m) / l }'
echo "  LAMMPS breakdown of the fibre run (one table per run command):"
sed -n '/^Section |/,/^Other/p' log.fibre | sed 's/^/    /'
