#!/bin/bash
# Accuracy against cost of the nonsmooth step: every state (a .sys/.lambda pair that
# bench/export_states.sh or `fix fibre_contact export` wrote) is replayed by fibre_accuracy
# with eight families of settings, each against the state's converged reference (projected
# Gauss-Seidel and semismooth Newton to a complementarity residual of 1e-10, cross-checked):
#   pgs        solver pgs, S sweeps
#   nncg       solver nncg (the sweeps with nonsmooth nonlinear CG), S sweeps
#   fbgs       solver fbgs (the sweeps with fibre-block corrections), S sweeps
#   apgd       solver apgd (accelerated projected gradient), S iterations
#   cg         the linear pass (body form, tree-preconditioned CG) then S sweeps (the
#              default before the sweeps alone)
#   cg+nncg    the same with the sweeps accelerated (sweep_cg yes)
#   pgs-tol    solver pgs stopped at its accuracy estimate A (tol A; the default is tol 1e-4)
#   cg-tol     solver cg stopped the same way
# for S and A in the lists below (tol none, and the cg families without the rescue, which a
# sweep_tol of 1e-14 would set off on every step). One CSV per state in the work directory, then
# bench/plot_accuracy.py draws the curves (velocity error against K-product equivalents) and
# prints the table of bench/README.md.
#
# Usage: bench/accuracy_study.sh [--states DIR] [--tool build/tools/fibre_accuracy]
#                                [--work /tmp/fibre_accuracy] [--png bench/accuracy_curves.png]
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
states=/tmp/fibre_states
tool=$src/build/tools/fibre_accuracy
work=/tmp/fibre_accuracy
png=$src/bench/accuracy_curves.png
while [ $# -gt 0 ]; do
  case $1 in
    -h|--help) awk 'NR == 1 { next } !/^#/ { exit } { sub(/^# ?/, ""); print }' "$0"; exit 0 ;;
    --states|--tool|--work|--png)
      [ $# -ge 2 ] || { echo "accuracy_study.sh: $1 needs a value" >&2; exit 2; }
      case $1 in
        --states) states=$2 ;; --tool) tool=$2 ;; --work) work=$2 ;; --png) png=$2 ;;
      esac
      shift 2 ;;
    *) echo "accuracy_study.sh: unknown option $1 (--help: the usage)" >&2; exit 2 ;;
  esac
done
mkdir -p "$work"
settings=()
for s in 5 10 20 50 100 200 500 1000; do
  settings+=(--setting "solver pgs tol none sweeps $s sweep_tol 1e-14")
  settings+=(--setting "solver nncg tol none sweeps $s sweep_tol 1e-14")
  settings+=(--setting "solver fbgs tol none sweeps $s sweep_tol 1e-14")
  settings+=(--setting "solver apgd tol none sweeps $s sweep_tol 1e-14")
done
for s in 0 5 10 20 50 100 200 500; do
  settings+=(--setting "solver cg tol none sweeps $s sweep_tol 1e-14 rescue_sweeps 0")
  settings+=(--setting "solver cg tol none sweep_cg yes sweeps $s sweep_tol 1e-14 rescue_sweeps 0")
done
for a in 1e-2 3e-3 1e-3 3e-4 1e-4; do
  settings+=(--setting "solver pgs tol $a")
  settings+=(--setting "solver cg tol $a")
done
settings+=(--setting "")
for sys in "$states"/*.sys; do
  name=$(basename "$sys" .sys)
  echo "== $name"
  # exit status 3: the two reference methods did not agree; the table still comes, flagged
  "$tool" "${sys%.sys}" --repeat 3 --csv "$work/$name.csv" "${settings[@]}" \
    > "$work/$name.txt" || echo "fibre_accuracy exit status $?: see $work/$name.txt"
  head -4 "$work/$name.txt"
done
# Debian's python3 has matplotlib (a python3 earlier on PATH may not)
py=/usr/bin/python3
[ -x "$py" ] || py=python3
"$py" "$src/bench/plot_accuracy.py" --png "$png" "$work"/*.csv
