#!/usr/bin/env bash
# Set everything up and run the whole test suite twice: an optimised build
# with -Wall -Wextra -Werror, then the same under AddressSanitizer and
# UndefinedBehaviorSanitizer.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
jobs=$(nproc)
for variant in release sanitize; do
  dir=build-test-$variant
  extra=()
  if [ "$variant" = sanitize ]; then
    extra=(-DCMAKE_BUILD_TYPE=Debug "-DSTICKSLIP_SANITIZE=address;undefined")
  else
    extra=(-DCMAKE_BUILD_TYPE=RelWithDebInfo)
  fi
  echo "== $variant build"
  cmake -S . -B "$dir" -DSTICKSLIP_WERROR=ON -DSTICKSLIP_BUILD_TESTS=ON "${extra[@]}" >/dev/null
  cmake --build "$dir" -j"$jobs"
  echo "== $variant tests"
  (cd "$dir" && UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
     ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j"$jobs")
done
if command -v clang-format >/dev/null; then
  echo "== format check"
  cmake --build build-test-release --target format-check
else
  echo "== format check skipped: no clang-format (apt-get install clang-format)"
fi
