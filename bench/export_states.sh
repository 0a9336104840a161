#!/bin/bash
# Step states: the contact systems of single time steps of the example scenes, exported with
# `fix fibre_contact ... export E prefix` (doc/system_format.md, version 2) for the accuracy
# study of the nonsmooth solver. Four states per N, each a .sys and a .lambda in the work
# directory:
#   material<N>_forming    the heap forming: 70% of the pour (fix pour's last insertion step)
#   material<N>_settled    the end of the deck's settling (tsettle after the last batch)
#   silo<N>_filled         the end of the fill, plug closed, just before the orifice opens
#   silo<N>_discharge      the discharge, halfway through the deck's tflow
# Every state step is a multiple of 50 (the nearest one, the last one before the deck's end
# of settling or fill); E is the largest common divisor of a scene's two steps, and each run
# stops right after its later step (material: -var tend, silo: -var tflow), so the states are
# those of the decks' full runs. One serial run per scene and N, one at a time.
#
# Usage: bench/export_states.sh [--N "1400 5000"] [--lmp build/fix/lmp_fibre]
#                               [--work /tmp/fibre_states] [--scenes "material silo"]
#                               [--var NAME VALUE ...]
# --var passes a deck variable to every run, for example `--var E 1e8` for the states of a
# stiff material (the decks' time step does not depend on E: it is set at Edt).
# The states go into the work directory, the runs into <work>/run_<scene><N>/ (their logs:
# <work>/<scene><N>.log, the exports not kept are deleted). <work>/states.txt lists every
# state in the work directory: step, simulated time, contacts, bodies (owned), and the
# solve of that step (its converged flag f_fc[10], Krylov iterations, relative residual,
# complementarity residual) with the run's non-converged steps up to it (f_fc[12]).
# The examples are copied, not changed; the copies get f_fc[10] and f_fc[12] in their thermo
# columns and a `fix print` line "fc_state ..." every E steps.
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
. "$src/bench/common.sh"
Ns="1400 5000"
lmp=$src/build/fix/lmp_fibre
work=/tmp/fibre_states
scenes="material silo"
vars=() # -var NAME VALUE for every run
while [ $# -gt 0 ]; do
  case $1 in
    -h|--help) usage "$0"; exit 0 ;;
    --N|--lmp|--work|--scenes)
      [ $# -ge 2 ] || { echo "$(basename "$0"): $1 needs a value" >&2; exit 2; }
      case $1 in
        --N) Ns=$2 ;;
        --lmp) lmp=$2 ;;
        --work) work=$2 ;;
        --scenes) scenes=$2 ;;
      esac
      shift 2 ;;
    --var)
      [ $# -ge 3 ] || { echo "$(basename "$0"): --var needs a name and a value" >&2; exit 2; }
      vars+=(-var "$2" "$3")
      shift 3 ;;
    *) echo "$(basename "$0"): unknown option $1 (--help: the usage)" >&2; exit 2 ;;
  esac
done
[ -x "$lmp" ] || { echo "$(basename "$0"): no LAMMPS binary $lmp (--lmp)" >&2; exit 2; }
lmp=$(cd "$(dirname "$lmp")" && pwd)/$(basename "$lmp") # the runs cd into the work directory
export OMP_NUM_THREADS=1
mkdir -p "$work"
work=$(cd "$work" && pwd)
grid=50

gcd() { local a=$1 b=$2 t; while [ "$b" -ne 0 ]; do t=$((a % b)); a=$b; b=$t; done; echo "$a"; }

# A copy of examples/<scene>/ in the current directory: thermo with f_fc[10], f_fc[12] and the
# fc_state line every `every` steps (0: none; the probe copy).
copy_deck() {  # scene every
  local scene=$1 every=$2
  cp "$src/examples/$scene/in.$scene" "$src/examples/$scene/run.$scene" \
     "$src/examples/$scene/scene.$scene" .
  sed -i 's/^variable  *fibre_thermo string .*/variable  fibre_thermo string "f_fc[1] f_fc[2] f_fc[3] f_fc[7] f_fc[10] f_fc[12] f_fc[13]"/' "in.$scene"
  if [ "$every" -gt 0 ]; then
    sed -i "s/^include  *run\.$scene/fix       fc_state all print $every \"fc_state step \$(step) time \$(time:%.10g) contacts \$(f_fc[3]) converged \$(f_fc[10]) iterations \$(f_fc[1]) residual \$(f_fc[2]:%.3e) complementarity \$(f_fc[13]:%.3e) nonconverged_steps \$(f_fc[12])\"\n&/" "in.$scene"
  fi
}

# The deck's schedule without running it (every `run` made `run 0`): prints
# "dt nsteps last_insertion" (material) or "dt nfill nflow" (silo).
probe() {  # scene N
  local scene=$1 n=$2 dir="$work/probe_$1$2"
  rm -rf "$dir" && mkdir -p "$dir" && cd "$dir"
  copy_deck "$scene" 0
  sed -i 's/^run .*/run 0/' "run.$scene"
  # shellcheck disable=SC2016  # LAMMPS variables, expanded by LAMMPS
  if [ "$scene" = material ]; then
    echo 'print "probe ${dt} ${nsteps}"' >> run.material
  else
    echo 'print "probe ${dt} ${nfill} ${nflow}"' >> run.silo
  fi
  "$lmp" -in "in.$scene" -var N "$n" "${vars[@]}" -echo none -log probe.log -screen none \
    > /dev/null 2>&1 ||
    { echo "probe of $scene $n failed: $dir/probe.log" >&2; exit 1; }
  local line last
  line=$(sed -n 's/^probe //p' probe.log)
  last=$(sed -n 's/^Particle insertion: .* by step \([0-9]*\)$/\1/p' probe.log)
  cd "$work" && rm -rf "$dir"
  if [ "$scene" = material ]; then echo "$line $last"; else echo "$line"; fi
}

# One run of the deck (extra -var arguments after `every`), then the two states kept.
run_scene() {  # scene N name1 step1 name2 step2 every [-var name value ...]
  local scene=$1 n=$2 name1=$3 s1=$4 name2=$5 s2=$6 every=$7
  shift 7
  local dir="$work/run_$scene$n" t0 t1
  rm -rf "$dir" && mkdir -p "$dir" && cd "$dir"
  copy_deck "$scene" "$every"
  echo "$scene $n: states at steps $s1 ($name1), $s2 ($name2); export every $every, ${vars[*]} $*"
  t0=$(date +%s)
  "$lmp" -in "in.$scene" -var N "$n" "${vars[@]}" "$@" -var fc_extra "export $every snap" \
    -echo none -log log.txt -screen none > out.txt 2>&1 ||
    { echo "$scene $n: run failed, see $dir/log.txt" >&2; exit 1; }
  t1=$(date +%s)
  echo "$scene $n: run took $((t1 - t0)) s wall"
  local s name
  for s in "$s1:$name1" "$s2:$name2"; do
    name=$scene${n}_${s#*:}
    s=${s%%:*}
    [ -f "snap.$s.0.sys" ] || { echo "$scene $n: no export at step $s in $dir" >&2; exit 1; }
    mv "snap.$s.0.sys" "$work/$name.sys"
    mv "snap.$s.0.lambda" "$work/$name.lambda"
  done
  rm -f snap.*.sys snap.*.lambda
  { echo "# export_states.sh: $scene N $n ${vars[*]}, wall $((t1 - t0)) s, $(basename "$lmp")," \
         "$(git -C "$src" describe --always --dirty 2>/dev/null || echo '?')"
    cat log.txt; } > "$work/$scene$n.log"
  cd "$work"
}

# Nearest multiple of the grid; the last multiple at or before.
near() { echo $(( ($1 + grid / 2) / grid * grid )); }
floor() { echo $(( $1 / grid * grid )); }

has_scene() { case " $scenes " in *" $1 "*) return 0 ;; *) return 1 ;; esac; }
for s in $scenes; do
  case $s in
    material|silo) ;;
    *) echo "$(basename "$0"): unknown scene $s (--scenes: material, silo)" >&2; exit 2 ;;
  esac
done

for n in $Ns; do
  if has_scene material; then
    # material: forming at 70% of the pour, settled at the deck's end
    sched=$(probe material "$n")
    read -r dt nsteps last <<< "$sched"
    s1=$(near $((last * 7 / 10)))
    s2=$(floor "$nsteps")
    tend=$(awk -v s="$s2" -v dt="$dt" 'BEGIN { printf "%.17g", s * dt }')
    run_scene material "$n" forming "$s1" settled "$s2" "$(gcd "$s1" "$s2")" -var tend "$tend"
  fi
  has_scene silo || continue
  # silo: filled at the end of the fill, discharge halfway through tflow
  sched=$(probe silo "$n")
  read -r dt nfill nflow <<< "$sched"
  s1=$(floor "$nfill")
  s2=$(near $((nfill + nflow / 2)))
  tflow=$(awk -v s=$((s2 - nfill)) -v dt="$dt" 'BEGIN { printf "%.17g", s * dt }')
  run_scene silo "$n" filled "$s1" discharge "$s2" "$(gcd "$s1" "$s2")" -var tflow "$tflow"
done

# states.txt: every state in the work directory, from its files and its run's fc_state line.
{
  printf '%-24s %6s %9s %8s %7s %6s %9s %5s %10s %15s %7s\n' file step time contacts bodies \
    owned converged iters residual complementarity nonconv
  for f in *_*.sys; do
    [ -f "$f" ] || continue
    base=${f%.sys}
    step=$(sed -n 's/^# fibre_contact impulses, step \([0-9]*\),.*/\1/p' "$base.lambda")
    log=${base%_*}.log
    awk -v f="$f" -v step="$step" -v logf="$log" -v key="${base%_*}" '
      $1 == "spook" { h = $2 }
      $1 == "bodies" { nb = $2; no = $3 }
      $1 == "contacts" { nc = $2; exit }
      END {
        conv = "?"; it = "?"; res = "?"; cr = "?"; nn = "?"
        while ((getline line < logf) > 0) {
          n = split(line, w, " ")
          if (w[1] == "fc_state" && w[3] == step) {
            for (i = 2; i < n; i += 2) v[w[i]] = w[i + 1]
            conv = v["converged"]; it = v["iterations"]; res = v["residual"]
            cr = v["complementarity"]; nn = v["nonconverged_steps"]
          }
        }
        printf "%s %d %-24s %6d %9.4f %8d %7d %6d %9s %5s %10s %15s %7s\n", key, step, f,
          step, step * h, nc, nb, no, conv, it, res, cr, nn
      }' "$f"
  done | sort -k1,1V -k2,2n | cut -d' ' -f3-
} > states.txt
cat states.txt
