#!/usr/bin/env bash
# A throwaway PostgreSQL cluster for tests, on loopback.
#   pg-throwaway.sh start DIR   initdb in a new temporary directory (under
#                               $TMPDIR, owned by the postgres user when run
#                               as root, since the server refuses to run as
#                               root), start it on 127.0.0.1 and a free
#                               port, trust authentication, no fsync; write
#                               its URI to DIR/uri and print it
#   pg-throwaway.sh stop DIR    stop it, remove its directory and DIR
#
# CTest: the fixture "pg" (tests/CMakeLists.txt: the tests pg_start and
# pg_stop, FIXTURES_SETUP / FIXTURES_CLEANUP pg) starts one cluster for
# every test that has FIXTURES_REQUIRED pg, and stops it after the last of
# them; `ctest -R store` runs both.  DIR is the build's tests/pg, which
# tests/CMakeLists.txt names SS_PG_URI_FILE for its uri file: a test reads
# the URI from there (test_store takes @FILE as its argument).  Tests share
# the cluster and may run side by side, so each should work in a database
# of its own (CREATE DATABASE through the URI, its name in place of the
# URI's /postgres), as test_store does; two daemons meant to share one
# store use the same database.
#
# Without PostgreSQL's server binaries (Debian: postgresql) start exits 77
# (CTest: skipped), and so do the tests that need the cluster, unless
# SS_REQUIRE_PG is set (CI), where they fail.
set -euo pipefail
cmd=${1:-} dir=${2:-}
if [ -z "$dir" ] || { [ "$cmd" != start ] && [ "$cmd" != stop ]; }; then
  echo "usage: $0 start|stop DIR" >&2
  exit 2
fi
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1 || true)
as_pg() {
  if [ "$(id -u)" = 0 ]; then
    su postgres -s /bin/sh -c "$1"
  else
    sh -c "$1"
  fi
}

if [ "$cmd" = stop ]; then
  data=$(cat "$dir/data" 2>/dev/null || true)
  if [ -n "$data" ] && [ -f "$data/db/postmaster.pid" ] && [ -n "$bin" ]; then
    as_pg "'$bin/pg_ctl' -D '$data/db' -m immediate -w stop" >/dev/null || true
  fi
  [ -n "$data" ] && rm -rf "$data"
  rm -rf "$dir"
  exit 0
fi

if [ -z "$bin" ] || [ ! -x "$bin/initdb" ]; then
  echo "PostgreSQL's server is not installed (Debian: postgresql): skipped"
  exit 77
fi
# a cluster left by a run that was cut short
[ -f "$dir/data" ] && "$0" stop "$dir"
mkdir -p "$dir"
data=$(mktemp -d "${TMPDIR:-/tmp}/stickslip-pg.XXXXXX")
echo "$data" >"$dir/data"
[ "$(id -u)" = 0 ] && chown postgres: "$data"
as_pg "'$bin/initdb' -D '$data/db' -A trust -U postgres --no-sync -E UTF8 \
  >'$data/initdb.log' 2>&1" || { cat "$data/initdb.log" >&2; exit 1; }
# A free port: one nothing answers on, from the ephemeral range; taken
# between the probe and the start by another, the start fails and the next
# one is tried.
for try in 1 2 3 4 5; do
  port=$((32768 + RANDOM % 28000))
  (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null && continue
  if as_pg "'$bin/pg_ctl' -D '$data/db' -l '$data/server.log' -w -t 30 \
    -o \"-p $port -k '$data' -c listen_addresses=127.0.0.1 -c fsync=off \
    -c full_page_writes=off\" start >/dev/null"; then
    uri="postgresql://postgres@127.0.0.1:$port/postgres"
    echo "$uri" >"$dir/uri"
    chmod 0644 "$dir/uri"
    echo "$uri"
    exit 0
  fi
done
cat "$data/server.log" >&2
exit 1
