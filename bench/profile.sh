#!/bin/sh
# Instruction counts per call of the hot paths (callgrind; the VM has no hardware counters for
# perf stat). Usage: bench/profile.sh [BUILD_DIR] [CONTACTS] [REPS]
# Prints, per target, instructions per call and per contact. Needs valgrind.
set -eu
build=${1:-build-perf}
contacts=${2:-15000}
reps=${3:-5}
exe=$build/bench/bench_profile
tmp=$(mktemp -d)
printf '%-18s %14s %12s\n' target Ir/call Ir/contact
for what in ${TARGETS:-fibres forest contact_fibre contact_tree body_fibre body_tree product_A product_K \
            apply_contact_tree apply_body_tree}; do
  valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.$what" --collect-atstart=no \
    --toggle-collect='*run_target*' "$exe" "$what" "$contacts" "$reps" > "$tmp/log.$what" 2>&1
  ir=$(sed -n 's/^summary: *//p' "$tmp/cg.$what")
  nc=$(sed -n 's/^[0-9]* bodies, \([0-9]*\) contacts$/\1/p' "$tmp/log.$what")
  awk -v w="$what" -v ir="$ir" -v r="$reps" -v nc="$nc" \
    'BEGIN { printf "%-18s %14.0f %12.1f\n", w, ir / r, ir / r / nc }'
done
echo "callgrind outputs in $tmp (callgrind_annotate $tmp/cg.TARGET)"
