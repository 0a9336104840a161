#!/usr/bin/env bash
# README command 1: install dependencies, build lmp_fibre, run the main granular example
# (the official LAMMPS pour deck converted to fix fibre_contact).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash cmake/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFIBRE_BUILD_FIX=ON -DFIBRE_BUILD_TESTS=ON \
  -DFIBRE_BUILD_BENCH=ON -DFIBRE_SANITIZE=OFF >/dev/null
cmake --build build -j"$(nproc)" --target lmp_fibre
cd examples/pour
"$root/build/fix/lmp_fibre" -in in.pour.fibre "$@"
