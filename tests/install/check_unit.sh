#!/usr/bin/env bash
# The systemd unit (packaging/stickslipd.service.in) as systemd reads it:
# written as the installation writes it, its ExecStart the daemon just
# built, and `systemd-analyze verify` must accept it without a word
# (directives and their values, the man page its Documentation= names).  Exit 77 (skipped) without
# systemd-analyze (scripts/setup.sh --test installs systemd).
# Usage: check_unit.sh STICKSLIPD SOURCE_DIR
set -euo pipefail
daemon=$1 src=$2
if ! command -v systemd-analyze >/dev/null; then
  echo "systemd_unit: no systemd-analyze (scripts/setup.sh --test)"
  exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/man/man1"
cp "$src/packaging/stickslipd.1" "$tmp/man/man1/"
sed "s|@CMAKE_INSTALL_FULL_BINDIR@|$(dirname "$(readlink -f "$daemon")")|" \
  "$src/packaging/stickslipd.service.in" >"$tmp/stickslipd.service"
# verify exits 0 on a directive it ignores: anything it says is a failure
said=$(MANPATH=$tmp/man: systemd-analyze verify "$tmp/stickslipd.service" 2>&1) || {
  echo "$said"
  exit 1
}
if [ -n "$said" ]; then
  echo "systemd_unit: systemd-analyze verify said:"
  echo "$said"
  exit 1
fi
echo "systemd_unit: systemd-analyze verify accepts the unit, silently"
