#!/usr/bin/env bash
# Set everything up and run the whole test suite twice: an optimised build
# with -Wall -Wextra -Werror, then the same under AddressSanitizer and
# UndefinedBehaviorSanitizer; then the core's tests against libstickslip
# built as a shared library.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --test
jobs=$(nproc)
for variant in release sanitize; do
  dir=build-test-$variant
  extra=()
  sets=()
  if [ "$variant" = sanitize ]; then
    extra=(-DCMAKE_BUILD_TYPE=Debug "-DSTICKSLIP_SANITIZE=address;undefined")
    # the search battery's brute force and the existence map are slow under
    # the sanitizers: the optimised build runs all 40 sets and 50x50 cells,
    # this one 2 sets of each half, 12x12 cells, an 8x8 map and 200000 of
    # the million random doubles of the number writer's test, and without
    # the slow proofs (test_search's slip-overshoot-stick proof of each set,
    # two of test_certify's: minutes each here)
    sets=(SS_SEARCH_SETS=2 SS_SLOW_PROOFS=0 SS_EXISTENCE_N=12 SS_MAP_N=8
      SS_NUMBERS_COUNT=200000)
  else
    extra=(-DCMAKE_BUILD_TYPE=RelWithDebInfo)
  fi
  echo "== $variant build"
  cmake -S . -B "$dir" -DSTICKSLIP_WERROR=ON -DSTICKSLIP_BUILD_TESTS=ON "${extra[@]}" >/dev/null
  cmake --build "$dir" -j"$jobs"
  echo "== $variant tests"
  (cd "$dir" && env "${sets[@]}" UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
     ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j"$jobs") | tee "$dir/ctest.log"
  # setup.sh --test installed every tool a test needs: a skipped test here
  # is a tool that failed to install, not a pass
  if grep -q '\*\*\*Skipped' "$dir/ctest.log"; then
    echo "== $variant: tests were skipped:" >&2
    grep '\*\*\*Skipped' "$dir/ctest.log" >&2
    exit 1
  fi
done
# The library as a shared object: it must link and work with only what its
# header exports (no test may reach a hidden symbol).
echo "== shared library build"
cmake -S . -B build-test-shared -DSTICKSLIP_WERROR=ON -DSTICKSLIP_BUILD_TESTS=ON \
  -DSTICKSLIP_BUILD_SERVER=OFF -DSTICKSLIP_BUILD_BENCH=OFF -DBUILD_SHARED_LIBS=ON \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build-test-shared -j"$jobs"
echo "== shared library tests"
# (4 sets of each half of the search battery, without the slow proofs)
(cd build-test-shared && SS_SEARCH_SETS=4 SS_SLOW_PROOFS=0 SS_EXISTENCE_N=12 \
   ctest --output-on-failure -j"$jobs" -R '^(core_|readme_)')
if command -v clang-format >/dev/null; then
  echo "== format check"
  cmake --build build-test-release --target format-check
else
  echo "== format check skipped: no clang-format (apt-get install clang-format)"
fi
