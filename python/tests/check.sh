#!/bin/sh
# The Python client's checks, run by CTest with Debian's python3 (where
# scripts/setup.sh --test installs python3-pytest and mypy):
#   check.sh pytest STICKSLIPD   the tests against a live daemon
#   check.sh mypy                mypy --strict on the package and its
#                                build backend
# Exits 77 (skipped) when the tool is missing.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
py=${STICKSLIP_PYTHON:-/usr/bin/python3}
case "$1" in
pytest)
  "$py" -c 'import pytest' 2>/dev/null || { echo "no python3-pytest: skipped"; exit 77; }
  exec "$py" -m pytest -q -p no:cacheprovider "$here" --stickslipd "$2" ;;
mypy)
  "$py" -m mypy --version >/dev/null 2>&1 || { echo "no mypy: skipped"; exit 77; }
  cd "$here/.." && exec "$py" -m mypy --strict --no-incremental stickslip \
    stickslip_build.py ;;
esac
echo "usage: check.sh pytest STICKSLIPD | mypy" >&2
exit 2
