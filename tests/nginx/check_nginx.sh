#!/usr/bin/env bash
# Replicas behind nginx, on loopback: nginx (docker/nginx.conf, its
# placeholders filled in) in front of three stickslipd; 500 computations
# through nginx from 8 clients at once, one replica killed (SIGKILL) while
# they run; every computation must be answered once, 200, and with the same
# answer a daemon gives directly.  Skipped (77) where nginx or python3 is
# not installed (scripts/setup.sh --test installs them).
# Usage: check_nginx.sh STICKSLIPD SOURCE_DIR
set -euo pipefail
bin=$1 src=$2
command -v nginx >/dev/null || command -v /usr/sbin/nginx >/dev/null ||
  { echo "nginx: not installed, skipped"; exit 77; }
command -v python3 >/dev/null || { echo "python3: not installed, skipped"; exit 77; }
nginx_bin=$(command -v nginx || echo /usr/sbin/nginx)
tmp=$(mktemp -d)
pids=()
cleanup() {
  [ -f "$tmp/nginx.pid" ] && kill "$(cat "$tmp/nginx.pid")" 2>/dev/null || true
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT

# three replicas and a direct daemon, on free ports
ports=()
for i in 0 1 2 3; do
  "$bin" --port 0 --quiet --trusted-proxy 127.0.0.1 2>"$tmp/d$i.log" &
  pids+=($!)
  disown $! # no job-control message when one is killed
done
for i in 0 1 2 3; do
  for _ in $(seq 100); do
    grep -q listening "$tmp/d$i.log" 2>/dev/null && break
    sleep 0.05
  done
  ports+=("$(sed -n 's/.*:\([0-9]*\)$/\1/p' "$tmp/d$i.log" | head -1)")
done
listen=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
servers=""
for i in 0 1 2; do
  servers+="server 127.0.0.1:${ports[$i]} max_fails=1 fail_timeout=5s; "
done
mkdir -p "$tmp/body" "$tmp/proxy" "$tmp/fastcgi" "$tmp/uwsgi" "$tmp/scgi"
sed -e "s|@PREFIX@|$tmp|g" -e "s|@LISTEN@|127.0.0.1:$listen|" \
  -e "s|@SERVERS@|$servers|" "$src/docker/nginx.conf" >"$tmp/nginx.conf"
"$nginx_bin" -t -q -p "$tmp" -c "$tmp/nginx.conf" -e "$tmp/error.log"
"$nginx_bin" -p "$tmp" -c "$tmp/nginx.conf" -e "$tmp/error.log"
for _ in $(seq 100); do
  [ -f "$tmp/nginx.pid" ] && break
  sleep 0.05
done

python3 - "$listen" "${ports[3]}" "${pids[1]}" <<'PY'
import json, os, signal, sys, threading, time, urllib.request
proxy, direct, victim = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])

def post(port, path, body, rid):
    req = urllib.request.Request(
        "http://127.0.0.1:%d%s" % (port, path), data=json.dumps(body).encode(),
        headers={"Content-Type": "application/json", "X-Request-Id": rid})
    with urllib.request.urlopen(req, timeout=60) as r:
        return r.status, r.headers.get("X-Request-Id"), json.loads(r.read())

# 500 computations: simulations of the paper's orbit from 500 states, and
# orbits from guesses at 500 values of ur
jobs = []
for i in range(500):
    if i % 2:
        jobs.append(("/simulate", {
            "params": {"chi": 0.2, "eta": 4, "us": 0.0724, "ur": 0.6178, "V": 1},
            "initial": [1.27 + 1e-3 * i, 4.36, -0.81, 1.0], "t_end": 200 + i,
            "events": False}))
    else:
        jobs.append(("/orbit", {
            "params": {"chi": 0.2, "eta": 4, "us": 0.0724,
                       "ur": 0.62 + 0.0005 * i, "V": 1},
            "guess": {"durations": [4.4975, 2.7227, 3.0513]},
            "finite_difference": False}))
answers = [None] * len(jobs)
errors = []
lock = threading.Lock()
nxt = [0]

def worker():
    while True:
        with lock:
            i = nxt[0]
            nxt[0] += 1
        if i >= len(jobs):
            return
        path, body = jobs[i]
        try:
            st, rid, ans = post(proxy, path, body, "job-%d" % i)
            if st != 200 or rid != "job-%d" % i:
                errors.append("job %d: status %d, id %s" % (i, st, rid))
            answers[i] = ans
        except Exception as e:
            errors.append("job %d: %s" % (i, e))

t0 = time.time()
threads = [threading.Thread(target=worker) for _ in range(8)]
for t in threads:
    t.start()
while nxt[0] < 150:
    time.sleep(0.01)
os.kill(victim, signal.SIGKILL)  # a replica dies with work in flight
killed_at = nxt[0]
for t in threads:
    t.join()
dt = time.time() - t0
if errors:
    sys.exit("nginx: %d of 500 failed, e.g. %s" % (len(errors), errors[:3]))
# the same answers from a daemon directly (what does not depend on timing)
def strip(a):
    a = dict(a)
    for k in ("seconds",):
        a.pop(k, None)
    return a
wrong = 0
for i, (path, body) in enumerate(jobs):
    st, _, ans = post(direct, path, body, "direct-%d" % i)
    if strip(ans) != strip(answers[i]):
        wrong += 1
if wrong:
    sys.exit("nginx: %d answers differ from the direct daemon's" % wrong)
print("nginx: 500 computations through 3 replicas in %.2f s, one replica "
      "killed after %d were sent; all answered once, 200, as the direct "
      "daemon answers" % (dt, killed_at))
PY
# the killed replica's requests went elsewhere: nginx logged the failures it
# sent on to another replica
retried=$(grep -c "upstream" "$tmp/error.log" || true)
echo "nginx: $retried upstream failures retried on another replica"
[ "$retried" -gt 0 ]
