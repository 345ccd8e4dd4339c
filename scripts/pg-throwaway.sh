#!/usr/bin/env bash
# A throwaway PostgreSQL cluster for tests, on loopback.
#   pg-throwaway.sh start DIR   initdb in DIR/data (owned by the postgres
#                               user when run as root), start it on
#                               127.0.0.1 and a free port, socket in DIR,
#                               trust authentication; write its URI to
#                               DIR/uri and print it
#   pg-throwaway.sh stop DIR    stop it and remove DIR
# The CTest fixture "pg" (tests/CMakeLists.txt) runs start and stop around
# the tests that require it (FIXTURES_REQUIRED pg); they read the URI from
# DIR/uri (DIR: the build's tests/pg).  Without PostgreSQL's server
# binaries (Debian: postgresql) start exits 77, and the tests that need it
# skip unless SS_REQUIRE_PG is set.
set -euo pipefail
cmd=${1:?start or stop} dir=${2:?a directory}
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1 || true)
if [ "$cmd" = stop ]; then
  if [ -f "$dir/data/postmaster.pid" ] && [ -n "$bin" ]; then
    if [ "$(id -u)" = 0 ]; then
      su postgres -s /bin/sh -c "'$bin/pg_ctl' -D '$dir/data' -m immediate stop" >/dev/null || true
    else
      "$bin/pg_ctl" -D "$dir/data" -m immediate stop >/dev/null || true
    fi
  fi
  rm -rf "$dir"
  exit 0
fi
[ "$cmd" = start ] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }
if [ -z "$bin" ] || [ ! -x "$bin/initdb" ]; then
  echo "PostgreSQL's server is not installed (Debian: postgresql): skipped"
  exit 77
fi
rm -rf "$dir"
mkdir -p "$dir"
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
as_pg() {
  if [ "$(id -u)" = 0 ]; then
    su postgres -s /bin/sh -c "$1"
  else
    sh -c "$1"
  fi
}
[ "$(id -u)" = 0 ] && chown postgres: "$dir"
as_pg "'$bin/initdb' -D '$dir/data' -A trust -U postgres --no-sync -E UTF8 >'$dir/initdb.log' 2>&1" ||
  { cat "$dir/initdb.log" >&2; exit 1; }
as_pg "'$bin/pg_ctl' -D '$dir/data' -l '$dir/server.log' -w -t 30 \
  -o \"-p $port -k '$dir' -c listen_addresses=127.0.0.1 -c fsync=off\" start >/dev/null" ||
  { cat "$dir/server.log" >&2; exit 1; }
uri="postgresql://postgres@127.0.0.1:$port/postgres"
echo "$uri" >"$dir/uri"
chmod 0644 "$dir/uri"
echo "$uri"
