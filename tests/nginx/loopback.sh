# shellcheck shell=bash disable=SC2034
# nginx with docker/nginx.conf on loopback, for the tests and bench/nginx.sh
# (sourced).  The configuration is run as it is, but for what differs on
# loopback: its two listen lines take free ports of 127.0.0.1, its one
# upstream server line becomes a line per replica port, and a throwaway
# certificate for 127.0.0.1 is made in the prefix's tls/.
#   nginx_loopback PREFIX SOURCE_DIR PORT...
# sets NGINX_HTTP and NGINX_TLS (ports) and NGINX_CA (the certificate to
# trust); nginx_stop stops it.  NGINX_UNLIMITED=1 drops the limit_req and
# limit_conn lines (a throughput benchmark from one address).
nginx_bin=$(command -v nginx || echo /usr/sbin/nginx)

# nginx_tools_or_skip: exit 77 (a skipped test) unless nginx, python3 and
# openssl are installed (scripts/setup.sh --test installs them).
nginx_tools_or_skip() {
  [ -x "$nginx_bin" ] || { echo "nginx: not installed, skipped"; exit 77; }
  command -v python3 >/dev/null || { echo "python3: not installed, skipped"; exit 77; }
  command -v openssl >/dev/null || { echo "openssl: not installed, skipped"; exit 77; }
}

free_port() {
  python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'
}

# sed_once FILE FROM TO: FROM (a fixed string) is one whole line of FILE
sed_once() {
  local n
  n=$(grep -cxF -- "$2" "$1" || true)
  [ "$n" = 1 ] || { echo "docker/nginx.conf: '$2' is on $n lines, not 1" >&2; return 1; }
  FROM=$2 TO=$3 python3 -c '
import os, sys
p = sys.argv[1]
lines = open(p).read().split("\n")
lines = [os.environ["TO"] if l == os.environ["FROM"] else l for l in lines]
open(p, "w").write("\n".join(lines))' "$1"
}

nginx_loopback() {
  local prefix=$1 src=$2 servers="" p
  shift 2
  for p in "$@"; do
    servers+="${servers:+$'\n'}        server 127.0.0.1:$p max_fails=1 fail_timeout=5s;"
  done
  NGINX_HTTP=$(free_port)
  NGINX_TLS=$(free_port)
  mkdir -p "$prefix/tls"
  openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=127.0.0.1 \
    -addext "subjectAltName=IP:127.0.0.1" -keyout "$prefix/tls/stickslip.key" \
    -out "$prefix/tls/stickslip.crt" 2>/dev/null
  NGINX_CA=$prefix/tls/stickslip.crt
  cp "$src/docker/nginx.conf" "$prefix/nginx.conf"
  sed_once "$prefix/nginx.conf" "        listen 8080;" "        listen 127.0.0.1:$NGINX_HTTP;"
  sed_once "$prefix/nginx.conf" "        listen 8443 ssl;" \
    "        listen 127.0.0.1:$NGINX_TLS ssl;"
  sed_once "$prefix/nginx.conf" \
    "        server stickslipd:8080 max_fails=1 fail_timeout=5s;" "$servers"
  if [ "${NGINX_UNLIMITED:-0}" = 1 ]; then
    sed -i -e '/^ *limit_req /d' -e '/^ *limit_conn /d' "$prefix/nginx.conf"
  fi
  "$nginx_bin" -t -q -p "$prefix" -c "$prefix/nginx.conf" -e "$prefix/error.log"
  "$nginx_bin" -p "$prefix" -c "$prefix/nginx.conf" -e "$prefix/error.log"
  for _ in $(seq 100); do
    [ -f "$prefix/nginx.pid" ] && return 0
    sleep 0.05
  done
  echo "nginx did not start: $(cat "$prefix/error.log")" >&2
  return 1
}

nginx_stop() { # nginx_stop PREFIX
  if [ -f "$1/nginx.pid" ]; then
    kill "$(cat "$1/nginx.pid")" 2>/dev/null || true
    for _ in $(seq 100); do
      [ -f "$1/nginx.pid" ] || return 0
      sleep 0.05
    done
  fi
}
