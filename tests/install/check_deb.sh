#!/usr/bin/env bash
# The Debian packages (packaging/deb.cmake) as an operator and a researcher
# meet them: a build configured as the packages are (prefix /usr, shared
# library), `cpack -G DEB`, then each package's control fields and files
# (dpkg-deb -I, -c); then installed and used: the README's program built
# with pkg-config against libstickslip-dev and run, and the daemon started
# (through its systemd unit where systemd runs, by hand otherwise) and
# asked for /health.
# Installed for real (dpkg -i, then purged) only where
# STICKSLIP_DISPOSABLE_MACHINE=1 says the machine may be changed (a
# container thrown away after); otherwise dpkg checks their dependencies
# against this machine (--dry-run as root, dpkg-query otherwise) and
# installs them into a root of their own with a database of its own
# (--instdir, --admindir; maintainer scripts run outside a chroot, as
# DPKG_ROOT says), where the .pc files and the daemon's run path find their
# files as they would under /, and purges them from it.
# Skipped (77) without dpkg-deb or cpack.
# Usage: check_deb.sh SOURCE_DIR BUILD_DIR C_COMPILER CMAKE CPACK
set -euo pipefail
# grep -q at the end of a pipeline, reading all of its input: grep -q stops
# at the first match, and under pipefail the writer then killed by SIGPIPE
# fails the pipeline (a unit file's later lines, readelf's later entries)
has_line() { grep "$@" >/dev/null; }
src=$1 work=$2 cc=$3 cmake=$4 cpack=$5
command -v dpkg-deb >/dev/null || { echo "dpkg-deb: not installed, skipped"; exit 77; }
[ -x "$cpack" ] || command -v "$cpack" >/dev/null ||
  { echo "cpack: not installed, skipped"; exit 77; }
want="slip 4.497497  overshoot 2.722666  stick 3.051267"
version=$(sed -n 's/^#define SS_VERSION_\(MAJOR\|MINOR\|PATCH\) \([0-9]*\)$/\2/p' \
  "$src/core/include/stickslip.h" | paste -sd.)
abi=${version%.*}
tmp=$(mktemp -d)
installed=0 pid=
cleanup() {
  [ -n "$pid" ] && kill "$pid" 2>/dev/null && wait "$pid" 2>/dev/null
  if [ "$installed" = 1 ]; then
    dpkg --purge stickslipd libstickslip-dev libstickslip0 >/dev/null || true
  fi
  rm -rf "$tmp"
}
trap cleanup EXIT
fail() { echo "deb: $*"; exit 1; }

# the packages, from a build of their own (kept between runs)
"$cmake" -S "$src" -B "$work" -DCMAKE_INSTALL_PREFIX=/usr -DBUILD_SHARED_LIBS=ON \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER="$cc" \
  -DSTICKSLIP_BUILD_TESTS=OFF -DSTICKSLIP_BUILD_BENCH=OFF >/dev/null
"$cmake" --build "$work" -j2 >/dev/null
rm -f "$work"/*.deb
(cd "$work" && "$cpack" -G DEB >/dev/null)
arch=$(dpkg --print-architecture)
ma=$(dpkg-architecture -qDEB_HOST_MULTIARCH 2>/dev/null || gcc -print-multiarch)
deb() { echo "$work/${1}_$version-1_$arch.deb"; }
debs=("$(deb libstickslip0)" "$(deb libstickslip-dev)" "$(deb stickslipd)")
for p in libstickslip0 libstickslip-dev stickslipd; do
  [ -f "$(deb $p)" ] || fail "no $(basename "$(deb $p)") among: $(ls "$work"/*.deb)"
done

# control fields
field() { dpkg-deb -f "$(deb "$1")" "$2"; }
for p in libstickslip0 libstickslip-dev stickslipd; do
  got="$(field $p Package) $(field $p Version) $(field $p Architecture)"
  [ "$got" = "$p $version-1 $arch" ] || fail "$p: $(dpkg-deb -f "$(deb $p)")"
  [ -n "$(field $p Maintainer)" ] || fail "$p: no maintainer"
  [ -n "$(field $p Description)" ] || fail "$p: no description"
done
has_dep() { # has_dep PACKAGE DEPENDENCY-PATTERN
  field "$1" Depends | tr ',' '\n' | sed 's/^ *//' | has_line -x "$2" ||
    fail "$1 depends on '$(field "$1" Depends)', not on $2"
}
has_dep libstickslip0 'libgsl27 (>= .*)'
has_dep libstickslip0 'libc6 (>= .*)'
has_dep libstickslip-dev "libstickslip0 (= $version-1)"
has_dep libstickslip-dev libgsl-dev
has_dep stickslipd "libstickslip0 (= $version-1)"
has_dep stickslipd 'libmicrohttpd12 (>= .*)'
has_dep stickslipd 'libjansson4 (>= .*)'
# the library's shlibs file and ldconfig trigger
dpkg-deb -I "$(deb libstickslip0)" shlibs |
  has_line -x "libstickslip $abi libstickslip0 (= $version-1)" ||
  fail "libstickslip0's shlibs: $(dpkg-deb -I "$(deb libstickslip0)" shlibs)"

dpkg-deb -I "$(deb libstickslip0)" triggers | has_line -x 'activate-noawait ldconfig' ||
  fail "libstickslip0 has no ldconfig trigger"

# files: each where Debian puts it, in one package only
files() { dpkg-deb -c "$(deb "$1")" | awk '{print $6}' | sed 's|^\./|/|' | grep -v '/$'; }
has() { # has PACKAGE PATH...: PACKAGE holds each PATH
  local p=$1 f
  shift
  for f in "$@"; do files "$p" | has_line -x "$f" || fail "$p lacks $f"; done
}
lib=/usr/lib/$ma
has libstickslip0 "$lib/libstickslip.so.$version" "$lib/libstickslip.so.$abi" \
  /usr/share/doc/libstickslip0/copyright
has libstickslip-dev /usr/include/stickslip.h "$lib/libstickslip.so" "$lib/libstickslip.a" \
  "$lib/pkgconfig/stickslip.pc" "$lib/pkgconfig/stickslip-static.pc" \
  "$lib/cmake/stickslip/stickslipConfig.cmake" /usr/share/doc/libstickslip-dev/copyright
has stickslipd /usr/bin/stickslipd /usr/share/man/man1/stickslipd.1 \
  /usr/lib/systemd/system/stickslipd.service /usr/share/doc/stickslipd/copyright
[ "$(files libstickslip0 | grep -vc '^/usr/share/doc/')" = 2 ] ||
  fail "libstickslip0 holds more than the library: $(files libstickslip0)"
dups=$(for p in libstickslip0 libstickslip-dev stickslipd; do files $p; done | sort | uniq -d)
[ -z "$dups" ] || fail "in two packages: $dups"
# the unit names the installed daemon
dpkg-deb --fsys-tarfile "$(deb stickslipd)" |
  tar -xO ./usr/lib/systemd/system/stickslipd.service | has_line -x 'ExecStart=/usr/bin/stickslipd.*' ||
  fail "the unit does not start /usr/bin/stickslipd"
echo "deb: $(basename -a "${debs[@]}" | paste -sd' '): fields and files ok"

# installed: for real on a disposable machine, else into a root of their own
if [ "${STICKSLIP_DISPOSABLE_MACHINE:-0}" = 1 ]; then
  [ "$(id -u)" = 0 ] || fail "STICKSLIP_DISPOSABLE_MACHINE=1 needs root for dpkg -i"
  installed=1
  dpkg -i "${debs[@]}" >/dev/null
  root=
  echo "deb: installed with dpkg -i"
else
  if [ "$(id -u)" = 0 ]; then
    dpkg --dry-run -i "${debs[@]}" >/dev/null || fail "dpkg -i would fail"
    echo "deb: dpkg --dry-run -i: would install here"
  else
    for d in $(for p in libstickslip0 libstickslip-dev stickslipd; do field $p Depends; done |
      tr ',' '\n' | sed 's/^ *\([^ ]*\).*/\1/' | sort -u | grep -v '^libstickslip'); do
      dpkg-query -W -f='${Status}' "$d" 2>/dev/null | has_line 'install ok installed' ||
        fail "would not install here: $d is not installed"
    done
    echo "deb: their dependencies are installed here"
  fi
  root=$tmp/root
  mkdir -p "$root" "$tmp/admin/updates" "$tmp/admin/info"
  touch "$tmp/admin/status" "$tmp/admin/available"
  own=(--admindir="$tmp/admin" --instdir="$root" --force-not-root
    --force-script-chrootless --force-depends)
  dpkg "${own[@]}" -i "${debs[@]}" >"$tmp/dpkg.log" 2>&1 ||
    fail "dpkg -i into a root of its own: $(cat "$tmp/dpkg.log")"
  for p in libstickslip0 libstickslip-dev stickslipd; do
    dpkg-query --admindir="$tmp/admin" -W -f='${Status}' $p | has_line 'install ok installed' ||
      fail "$p: $(dpkg-query --admindir="$tmp/admin" -W -f='${Status}' $p)"
  done
  echo "deb: installed with dpkg -i into a root of their own (STICKSLIP_DISPOSABLE_MACHINE=1: here)"
fi

# the README's program, with pkg-config, as its .pc file says
if [ -n "$root" ]; then
  export PKG_CONFIG_PATH=$root$lib/pkgconfig
fi
# shellcheck disable=SC2046
"$cc" -o "$tmp/example" "$src/tests/example/example.c" \
  $(pkg-config --cflags --libs stickslip) \
  -Wl,-rpath,"$(pkg-config --variable=libdir stickslip)"
readelf -d "$tmp/example" | has_line "NEEDED.*libstickslip.so.$abi" ||
  fail "the program does not use the shared library"
out=$("$tmp/example")
case $out in *"$want"*) ;; *) fail "the program printed: $out" ;; esac
echo "deb: the README's program, built with pkg-config $(pkg-config --modversion stickslip): ok"

# the daemon: through its unit where systemd runs, by hand otherwise
health() { # health PORT: /health answers 200 (bash's /dev/tcp: no HTTP client needed)
  { exec 3<>"/dev/tcp/127.0.0.1/$1"; } 2>/dev/null || return 1
  printf 'GET /health HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n' >&3
  timeout 5 cat <&3 >"$tmp/health"
  exec 3<&-
  head -1 "$tmp/health" | has_line '^HTTP/1.1 200' && grep -q '"status":"ok"' "$tmp/health"
}
if [ -z "$root" ] && [ -d /run/systemd/system ]; then
  systemctl start stickslipd
  ok=0
  for _ in $(seq 100); do health 8080 && { ok=1; break; }; sleep 0.1; done
  systemctl stop stickslipd
  [ "$ok" = 1 ] || fail "the unit's daemon did not answer: $(systemctl status stickslipd || true)"
  echo "deb: stickslipd through systemctl: /health ok"
else
  "$root/usr/bin/stickslipd" --port 0 --no-jobs 2>"$tmp/d.log" &
  pid=$!
  for _ in $(seq 200); do grep -q listening "$tmp/d.log" && break; sleep 0.05; done
  port=$(sed -n 's/.*:\([0-9]*\)$/\1/p' "$tmp/d.log" | head -1)
  [ -n "$port" ] || fail "the daemon did not start: $(cat "$tmp/d.log")"
  health "$port" || fail "/health: $(cat "$tmp/health" 2>/dev/null)"
  # it runs the packaged library, not one of the build tree
  grep -q "$root$lib/libstickslip.so.$version" "/proc/$pid/maps" ||
    fail "the daemon did not load the packaged library"
  echo "deb: $root/usr/bin/stickslipd by hand: /health ok"
fi
# and removed: nothing of theirs left but the directories others share
if [ -n "$root" ]; then
  kill "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  pid=
  dpkg "${own[@]}" --purge stickslipd libstickslip-dev libstickslip0 >"$tmp/dpkg.log" 2>&1 ||
    fail "dpkg --purge: $(cat "$tmp/dpkg.log")"
  left=$(find "$root" -type f)
  [ -z "$left" ] || fail "left after --purge: $left"
  echo "deb: purged"
fi
echo "deb: ok"
