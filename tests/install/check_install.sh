#!/usr/bin/env bash
# The installation works as a user meets it: install the build into a fresh
# prefix, then build the guide's example program against the installed
# copy, once with pkg-config and once with find_package(stickslip), and run
# both; check what else is installed (the static library beside a shared
# one, the daemon, its man page, the systemd unit, the user's guide).
# Usage: check_install.sh BUILD_DIR SOURCE_DIR C_COMPILER CMAKE
set -euo pipefail
# grep -q at the end of a pipeline, reading all of its input: grep -q stops
# at the first match, and under pipefail the writer then killed by SIGPIPE
# fails the pipeline (a unit file's later lines, readelf's later entries)
has_line() { grep "$@" >/dev/null; }
build=$1 src=$2 cc=$3 cmake=$4
want="slip 4.497497  overshoot 2.722666  stick 3.051267"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
"$cmake" --install "$build" --prefix "$prefix" >/dev/null
libdir=$(dirname "$(find "$prefix" -name stickslip.pc -print -quit)")/..
libdir=$(cd "$libdir" && pwd)
test -f "$prefix/include/stickslip.h"
test -f "$libdir/libstickslip.a" || { echo "no static library"; exit 1; }
test -f "$prefix/share/doc/stickslip/LICENSE"
# the user's guide, when the build made it (mkdocs installed)
if [ -f "$build/docs/site/index.html" ]; then
  test -f "$prefix/share/doc/stickslip/html/index.html" ||
    { echo "the user's guide is not installed"; exit 1; }
fi

# pkg-config, as stickslip.pc's comment says: a shared library outside the
# linker's search path is found with the run path it names (without one
# the program does not start), stickslip-static.pc links the archive, and
# --static with -static gives a program that needs no shared library
export PKG_CONFIG_PATH=$libdir/pkgconfig
runs() { # runs BINARY: it prints the orbit
  local out
  out=$("$@" 2>&1) || { echo "$1: $out"; return 1; }
  case $out in *"$want"*) ;; *) echo "$1 printed: $out"; return 1 ;; esac
}
needs_lib() { readelf -d "$1" | has_line 'NEEDED.*libstickslip'; }
# a static-only installation: stickslip.pc needs --static (the libraries
# libstickslip.a uses)
kind=static static=--static
if [ -e "$libdir/libstickslip.so" ]; then
  kind=shared static=
  soname=$(readelf -d "$libdir/libstickslip.so" | sed -n 's/.*SONAME.*\[\(.*\)\]/\1/p')
  case $soname in libstickslip.so.[0-9]*) ;; *) echo "soname $soname"; exit 1 ;; esac
  # shellcheck disable=SC2046
  "$cc" -o "$tmp/example_norpath" "$src/tests/example/example.c" \
    $(pkg-config --cflags --libs stickslip)
  needs_lib "$tmp/example_norpath"
  if out=$("$tmp/example_norpath" 2>&1); then
    echo "a program linked without a run path started: $out"; exit 1
  fi
  case $out in *"$soname: cannot open shared object file"*) ;;
    *) echo "without a run path: $out"; exit 1 ;; esac
  LD_LIBRARY_PATH=$(pkg-config --variable=libdir stickslip) runs "$tmp/example_norpath"
fi
# shellcheck disable=SC2046,SC2086
"$cc" -o "$tmp/example_pc" "$src/tests/example/example.c" \
  $(pkg-config $static --cflags --libs stickslip) \
  -Wl,-rpath,"$(pkg-config --variable=libdir stickslip)"
runs "$tmp/example_pc"
# shellcheck disable=SC2046
"$cc" -o "$tmp/example_pc_static" "$src/tests/example/example.c" \
  $(pkg-config --cflags --libs stickslip-static)
! needs_lib "$tmp/example_pc_static" || { echo "stickslip-static linked the shared library"; exit 1; }
runs "$tmp/example_pc_static"
# shellcheck disable=SC2046
"$cc" -static -o "$tmp/example_static" "$src/tests/example/example.c" \
  $(pkg-config --static --cflags --libs stickslip)
! readelf -d "$tmp/example_static" | has_line NEEDED ||
  { echo "pkg-config --static with -static linked a shared library"; exit 1; }
runs "$tmp/example_static"
echo "pkg-config: $(pkg-config --modversion stickslip), $kind; stickslip-static and --static -static: static"

# find_package, asking for the header's major.minor version (the ABI)
abi=$(sed -n 's/^#define SS_VERSION_\(MAJOR\|MINOR\) \([0-9]*\)$/\2/p' \
  "$src/core/include/stickslip.h" | paste -sd.)
mkdir "$tmp/consumer"
cp "$src/tests/example/example.c" "$tmp/consumer/"
cat >"$tmp/consumer/CMakeLists.txt" <<CM
cmake_minimum_required(VERSION 3.16)
project(consumer C)
find_package(stickslip $abi REQUIRED)
add_executable(example example.c)
target_link_libraries(example PRIVATE stickslip::stickslip)
CM
"$cmake" -S "$tmp/consumer" -B "$tmp/consumer/build" -DCMAKE_C_COMPILER="$cc" \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_RPATH="$libdir" >/dev/null
"$cmake" --build "$tmp/consumer/build" >/dev/null
runs "$tmp/consumer/build/example"
echo "find_package: ok"

# the daemon, when it was built: it runs from the prefix, with its man page
# and a unit systemd accepts
if [ -x "$prefix/bin/stickslipd" ]; then
  "$prefix/bin/stickslipd" --version
  man -l "$prefix/share/man/man1/stickslipd.1" >/dev/null 2>&1 ||
    { command -v man >/dev/null && { echo "man page"; exit 1; }; }
  # every flag of --help is in the man page
  for f in $("$prefix/bin/stickslipd" --help 2>&1 | grep -o -- '--[a-z-]*' | sort -u); do
    grep -q -- "$(echo "$f" | sed 's/-/\\\\-/g')" "$prefix/share/man/man1/stickslipd.1" ||
      { echo "the man page lacks $f"; exit 1; }
  done
  unit=$(find "$prefix" -name stickslipd.service -print -quit)
  test -n "$unit"
  grep -q "ExecStart=$prefix/bin/stickslipd" "$unit"
  if command -v systemd-analyze >/dev/null; then
    MANPATH=$prefix/share/man: systemd-analyze verify "$unit"
    echo "systemd-analyze verify: ok"
  else
    echo "systemd-analyze verify: skipped, no systemd-analyze (scripts/setup.sh --test)"
  fi
fi
echo "install: ok"
