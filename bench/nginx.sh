#!/usr/bin/env bash
# Throughput of stickslipd replicas behind nginx (docker/nginx.conf) on this
# machine: one daemon directly, then 1, 2 and 3 replicas behind nginx, each
# serving the same computations from 8 clients at once: full orbit searches
# (about 5 ms of CPU each) and cheap solves from a guess (about 0.1 ms).
# Writes bench/results/nginx.md.
# Usage: bash bench/nginx.sh PATH/stickslipd
set -euo pipefail
bin=$1
src=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null; nginx_stop "$tmp/nginx"; rm -rf "$tmp"' EXIT
start_daemons() { # n -> ports in $ports
  ports=()
  for i in $(seq "$1"); do
    "$bin" --port 0 --quiet --trusted-proxy 127.0.0.1 2>"$tmp/d$i.log" &
    disown $!
    for _ in $(seq 100); do grep -q listening "$tmp/d$i.log" && break; sleep 0.05; done
    ports+=("$(sed -n 's/.*:\([0-9]*\)$/\1/p' "$tmp/d$i.log" | head -1)")
  done
}
stop_all() {
  nginx_stop "$tmp/nginx"
  pkill -f "$bin --port 0 --quiet --trusted-proxy 127.0.0.1" 2>/dev/null || true
  sleep 0.3
}
# docker/nginx.conf as tests/nginx runs it, without its per-address limits:
# the clients here are 8 threads on one address, far over 100 requests a
# second
# shellcheck source=tests/nginx/loopback.sh
. "$src/tests/nginx/loopback.sh"
start_nginx() { # listen port in $listen
  rm -rf "$tmp/nginx"
  mkdir -p "$tmp/nginx"
  NGINX_UNLIMITED=1 nginx_loopback "$tmp/nginx" "$src" "${ports[@]}"
  listen=$NGINX_HTTP
}
drive() { # port -> "search_rps cheap_rps"
  python3 - "$1" <<'PY'
import json, sys, threading, time, urllib.request
port = int(sys.argv[1])
def run(bodies, path):
    nxt = [0]; lock = threading.Lock(); bad = []
    def w():
        while True:
            with lock:
                i = nxt[0]; nxt[0] += 1
            if i >= len(bodies): return
            req = urllib.request.Request("http://127.0.0.1:%d%s" % (port, path),
                data=json.dumps(bodies[i]).encode(),
                headers={"Content-Type": "application/json"})
            try:
                with urllib.request.urlopen(req, timeout=60) as r:
                    r.read()
            except Exception as e:
                bad.append(e)
    t0 = time.time()
    ts = [threading.Thread(target=w) for _ in range(8)]
    [t.start() for t in ts]; [t.join() for t in ts]
    if bad: sys.exit("bench: %d failed: %s" % (len(bad), bad[0]))
    return len(bodies) / (time.time() - t0)
P = {"chi": 0.2, "eta": 4, "us": 0.0724, "V": 1}
search = [{"params": dict(P, ur=0.62 + 0.002 * i), "kind": "overshoot",
           "finite_difference": False} for i in range(200)]
cheap = [{"params": dict(P, ur=0.62 + 0.0002 * i),
          "guess": {"durations": [4.4975, 2.7227, 3.0513]},
          "finite_difference": False} for i in range(2000)]
print("%.0f %.0f" % (run(search, "/orbit"), run(cheap, "/orbit")))
PY
}
rows=""
start_daemons 1
read -r s c < <(drive "${ports[0]}")
rows+="| one daemon, directly | $s | $c |"$'\n'
stop_all
for n in 1 2 3; do
  start_daemons "$n"
  start_nginx
  read -r s c < <(drive "$listen")
  rows+="| nginx + $n replica(s) | $s | $c |"$'\n'
  stop_all
done
cores=$(nproc)
cat >"$src/bench/results/nginx.md" <<MD
# Replicas behind nginx

\`bash bench/nginx.sh\` on a $cores-core machine, one run: requests per second from 8
clients at once, each daemon with its default workers (one per core).
"search": /orbit full searches (kind overshoot, about 5 ms of CPU each);
"guess": /orbit solves from a guess (about 0.1 ms each).

| setup | search (req/s) | guess (req/s) |
| --- | ---: | ---: |
$rows
MD
cat "$src/bench/results/nginx.md"
