#!/usr/bin/env bash
# The whole test suite (README command 2): installs dependencies, builds, runs
#   1. ctest on the normal build: unit tests, report binaries, end-to-end lmp_fibre and
#      liggghts_fibre runs (serial and mpirun -np 2/4);
#   2. the unit tests again on an ASan+UBSan build;
#   3. the system-file reader's libFuzzer target, briefly;
# after checking that the C++ sources follow .clang-format.
# Exits non-zero on any failure.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
jobs="$(nproc)"

bash cmake/install-deps.sh

echo "== format (clang-format --dry-run with .clang-format) =="
mapfile -t sources < <(find fix liggghts solver tools tests bench -name '*.cpp' -o -name '*.hpp' -o \
  -name '*.h' | sort)
clang-format --style=file --dry-run --Werror "${sources[@]}"
echo "format: ${#sources[@]} files follow .clang-format"

echo "== normal build =="
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFIBRE_BUILD_FIX=ON -DFIBRE_BUILD_LIGGGHTS=ON \
  -DFIBRE_BUILD_TESTS=ON -DFIBRE_BUILD_BENCH=ON -DFIBRE_SANITIZE=OFF >/dev/null
cmake --build build -j"$jobs"
cmake --build build --target bench -j"$jobs"
(cd build && ctest --output-on-failure -j"$jobs")

echo "== sanitizer build (ASan + UBSan), unit tests =="
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS="-O1" -DFIBRE_SANITIZE=ON \
  -DFIBRE_BUILD_FIX=OFF -DFIBRE_BUILD_LIGGGHTS=OFF -DFIBRE_BUILD_BENCH=OFF >/dev/null
cmake --build build-asan -j"$jobs"
(cd build-asan && ctest --output-on-failure -j"$jobs" -L unit)

echo "== fuzzing the system reader (libFuzzer) =="
CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFIBRE_FUZZ=ON \
  -DFIBRE_BUILD_FIX=OFF -DFIBRE_BUILD_LIGGGHTS=OFF -DFIBRE_BUILD_TESTS=OFF -DFIBRE_BUILD_BENCH=OFF >/dev/null
cmake --build build-fuzz -j"$jobs" --target fuzz_system_reader
mkdir -p build-fuzz/corpus
cp tests/fuzz/corpus/* build-fuzz/corpus/ 2>/dev/null || true
./build-fuzz/tests/fuzz/fuzz_system_reader -max_total_time="${FIBRE_FUZZ_SECONDS:-30}" \
  -rss_limit_mb=2048 build-fuzz/corpus
echo "fuzz: fuzz_system_reader ran ${FIBRE_FUZZ_SECONDS:-30} s without a crash"

echo "test suite: all stages passed"
