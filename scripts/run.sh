#!/usr/bin/env bash
# Set everything up and run stickslipd (default http://127.0.0.1:8080).
# Extra arguments go to stickslipd, e.g.: scripts/run.sh --port 9000
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DSTICKSLIP_BUILD_TESTS=OFF >/dev/null
cmake --build build -j"$(nproc)" --target stickslipd
exec ./build/server/stickslipd "$@"
