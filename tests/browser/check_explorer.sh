#!/usr/bin/env bash
# The explorer in a real browser: start the daemon on a free port, drive
# Debian's chromium through the page (explorer.test.mjs, puppeteer-core
# and axe-core pinned in package-lock.json), stop the daemon.  Exit 77 (skipped) when
# chromium, node or the test's node_modules are missing (scripts/setup.sh
# --test installs them).
# Usage: check_explorer.sh PATH/stickslipd SOURCE_DIR OUT_DIR
set -euo pipefail
bin=$1 src=$2 out=$3
here=$src/tests/browser
if ! command -v node >/dev/null || [ ! -x "${CHROMIUM:-/usr/bin/chromium}" ] ||
  [ ! -d "$here/node_modules/puppeteer-core" ] || [ ! -d "$here/node_modules/axe-core" ]; then
  echo "explorer: chromium, node or tests/browser/node_modules missing (scripts/setup.sh --test)"
  exit 77
fi
mkdir -p "$out"
log=$(mktemp)
state=$(mktemp -d)
# a compute limit that a daemon built with the sanitizers meets for the
# page's map (the default 10 s is for the optimised build); its jobs (the
# page's maps and basins) in a store of its own
"$bin" --port 0 --quiet --max-seconds 120 --state-dir "$state" 2>"$log" &
pid=$!
trap 'kill $pid 2>/dev/null; wait $pid 2>/dev/null; rm -rf "$log" "$state"' EXIT
for _ in $(seq 100); do
  url=$(grep -o 'http://[^ ]*' "$log" | head -1 || true)
  [ -n "$url" ] && break
  sleep 0.05
done
[ -n "$url" ] || { echo "the daemon did not start"; cat "$log"; exit 1; }
cd "$here"
node explorer.test.mjs "${url%/}" "$out"
