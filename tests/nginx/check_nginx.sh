#!/usr/bin/env bash
# Replicas behind nginx, on loopback: nginx (docker/nginx.conf, run by
# loopback.sh with its ports and a throwaway certificate) in front of three
# stickslipd; 500 computations over TLS from 8 clients at once (8 addresses,
# each within the rate limit), one replica killed (SIGKILL) while they run;
# every computation must be answered once, 200, and with the same answer a
# daemon gives directly.  Then one address over the rate limit gets 429s.
# Skipped (77) where nginx, openssl or python3 is not installed
# (scripts/setup.sh --test installs them).
# Usage: check_nginx.sh STICKSLIPD SOURCE_DIR
set -euo pipefail
bin=$1 src=$2
# shellcheck source=tests/nginx/loopback.sh
. "$src/tests/nginx/loopback.sh"
nginx_tools_or_skip
tmp=$(mktemp -d)
pids=()
cleanup() {
  nginx_stop "$tmp"
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
nginx_loopback "$tmp" "$src" "${ports[0]}" "${ports[1]}" "${ports[2]}"

python3 - "$NGINX_TLS" "${ports[3]}" "${pids[1]}" "$NGINX_CA" "$NGINX_HTTP" <<'PY'
import http.client, json, os, signal, ssl, sys, threading, time
proxy, direct, victim = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
tls = ssl.create_default_context(cafile=sys.argv[4])
plain = int(sys.argv[5])

def connect(port, source="127.0.0.1", secure=False):
    if secure:
        return http.client.HTTPSConnection("127.0.0.1", port, timeout=60,
                                           source_address=(source, 0),
                                           context=tls)
    return http.client.HTTPConnection("127.0.0.1", port, timeout=60,
                                      source_address=(source, 0))

def request(conn, method, path, body=None, rid=None):
    headers = {"Content-Type": "application/json"}
    if rid:
        headers["X-Request-Id"] = rid
    conn.request(method, path, body=body and json.dumps(body).encode(),
                 headers=headers)
    r = conn.getresponse()
    return r.status, r.headers, r.read()

def post(port, path, body, rid, conn=None):
    conn = conn or connect(port)
    st, headers, data = request(conn, "POST", path, body, rid)
    return st, headers.get("X-Request-Id"), json.loads(data)

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

def worker(k):
    # each client from an address of its own, over TLS, keeping its
    # connection while nginx keeps it
    conn = connect(proxy, "127.0.0.%d" % (10 + k), secure=True)
    while True:
        with lock:
            i = nxt[0]
            nxt[0] += 1
        if i >= len(jobs):
            return
        path, body = jobs[i]
        try:
            st, rid, ans = post(proxy, path, body, "job-%d" % i, conn)
            if st != 200 or rid != "job-%d" % i:
                errors.append("job %d: status %d, id %s" % (i, st, rid))
            answers[i] = ans
        except Exception as e:
            errors.append("job %d: %s" % (i, e))
            conn.close()

t0 = time.time()
threads = [threading.Thread(target=worker, args=(k,)) for k in range(8)]
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
print("nginx: 500 computations over TLS through 3 replicas in %.2f s, one "
      "replica killed after %d were sent; all answered once, 200, as the "
      "direct daemon answers" % (dt, killed_at))

# The rate limit: 600 requests at once from one address, over 4
# connections, well past 100 a second and a burst of 200.
codes = []
def hammer():
    c = connect(plain, "127.0.0.99")
    for _ in range(150):
        st, headers, data = request(c, "GET", "/health")
        codes.append(st)
        if st == 429:
            problem = json.loads(data)
            if (problem.get("status") != 429 or headers.get("Retry-After") != "1"
                    or "problem+json" not in headers.get("Content-Type", "")):
                sys.exit("nginx: a 429 of the limit: %r %r" % (dict(headers), data))
t0 = time.time()
threads = [threading.Thread(target=hammer) for _ in range(4)]
for t in threads:
    t.start()
for t in threads:
    t.join()
dt = time.time() - t0
limited, ok = codes.count(429), codes.count(200)
# 100/s past a burst of 200: at most about 200 + 100 dt answered
if limited == 0 or ok + limited != 600 or ok > 200 + 100 * dt + 10:
    sys.exit("nginx: 600 requests from one address in %.2f s: %d answered, "
             "%d limited (429)" % (dt, ok, limited))
print("nginx: 600 requests from one address in %.2f s: %d answered, %d got "
      "429 (100 a second, bursts of 200)" % (dt, ok, limited))
PY
# the killed replica's requests went elsewhere: nginx logged the failures it
# sent on to another replica
retried=$(grep -c "upstream" "$tmp/error.log" || true)
echo "nginx: $retried upstream failures retried on another replica"
[ "$retried" -gt 0 ]
