#!/bin/bash
# Exports the 10 contact systems of the thesis reproduction (silo and material, N = 350, 700,
# 1400, 2600, 5000) from the decks in examples/silo and examples/material into $SYSDIR
# (default examples/thesis/systems/{silo,material}N.{sys,lambda}). make_results.py never runs
# this; it only reads the systems.
#
#   bash examples/thesis/export.sh [LMP] [NAME ...]     e.g.  export.sh "" material700 silo350
#
# Each deck runs with its own defaults (the time it simulates is its own: the emitter's batches
# plus its settling time) and `fix fibre_contact ... export 100 snap` (fc_extra); the system
# kept is the LAST one exported, i.e. the last multiple of 100 steps of:
# - silo: the fill (plug closed, every batch poured, tsettle = 5 s of settling; the discharge
#   is not run: tflow 0) -- the filled funnel just before the orifice opens;
# - material: the whole deck (every batch poured, tsettle = 4 s of settling) -- the finished
#   pile on the plane.
# The step, the time and the deck's own schedule line are printed and kept in
# $SYSDIR/NAME.log (the deck's log). Runs at most JOBS (default 2) simulations at once, niced.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
LMP="${1:-}"
[ -n "$LMP" ] || LMP="$root/build/fix/lmp_fibre"
shift || true
SYSDIR="${SYSDIR:-$here/systems}"
WORK="${WORK:-/tmp/fibre_thesis_export}"
JOBS="${JOBS:-2}"
EVERY=100
mkdir -p "$SYSDIR" "$WORK"

export_one() {  # scene N
  local scene=$1 n=$2 dir="$WORK/$1$2"
  rm -rf "$dir" && mkdir -p "$dir" && cp "$root/examples/$scene"/* "$dir/"
  if [ "$scene" = material ]; then
    (cd "$dir" && nice -n 5 "$LMP" -in in.material -var N "$n" \
        -var fc_extra "export $EVERY snap" > log.txt 2>&1)
  else
    (cd "$dir" && nice -n 5 "$LMP" -in in.silo -var N "$n" -var tflow 0 \
        -var fc_extra "export $EVERY snap" > log.txt 2>&1)
  fi
  local last
  last=$(ls "$dir" | sed -n 's/^snap\.\([0-9]*\)\.0\.sys$/\1/p' | sort -n | tail -1)
  [ -n "$last" ] || { echo "$scene$n: no export (see $dir/log.txt)"; return 1; }
  cp "$dir/snap.$last.0.sys" "$SYSDIR/$scene$n.sys"
  cp "$dir/snap.$last.0.lambda" "$SYSDIR/$scene$n.lambda"
  { echo "# export.sh: $scene N=$n, kept step $last of $(git -C "$root" describe --always --dirty 2>/dev/null || echo '?')";
    grep -E "^(silo|material): N|Particle insertion" "$dir/log.txt" || true
    echo "# thermo line at or before step $last:"
    awk -v s="$last" '$1 ~ /^[0-9]+$/ && NF > 6 && $1 + 0 <= s + 0' "$dir/log.txt" | tail -1
  } > "$SYSDIR/$scene$n.log"
  rm -f "$dir"/snap.*
  echo "$scene$n: step $last -> $SYSDIR/$scene$n.sys"
}

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  for n in 350 700 1400 2600 5000; do targets+=("silo$n" "material$n"); done
fi
for t in "${targets[@]}"; do
  scene=${t%%[0-9]*}; n=${t#"$scene"}
  while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do sleep 5; done
  export_one "$scene" "$n" &
done
wait
