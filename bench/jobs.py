#!/usr/bin/env python3
"""Jobs against the same work answered synchronously, over HTTP.

1. A 200x200 existence map of the overshoot orbits (ur/us 1.5-15 and chi
   0.04-0.96, eta 4, us 0.0724, V 1): POST /map synchronously (the daemon
   started with --max-seconds large enough), then the same body with
   Prefer: respond-async, polled until successful and its results read.
   The store's overhead is the job's wall time over the synchronous one;
   the two answers are compared cell by cell (the "seconds" of the done
   line aside).  With --repeat N the two run N times each, in turn (the
   machine may be shared: a load that comes and goes falls on both), and
   the medians are reported, wall time and the daemon's CPU time.
2. A sweep of ITEMS /orbit requests (each from a guess: the overshoot orbit
   continued along ur) as one /batch job: the wall time from the POST to
   the last line read, and items per second.
Both on 1 and on 2 replicas sharing one store (sqlite in a temporary
directory; or --store URI for a PostgreSQL).  Each daemon computes on one
thread (--map-threads 1, --job-workers 1), so that the synchronous map and
the job on one replica use the same CPU and their ratio is the cost of
cutting and storing; two replicas compute a job's chunks on two threads.
The machine has 2 cores, so two replicas can at most double that.

Usage: bench/jobs.py STICKSLIPD [results_dir] [--cells N] [--items N]
                     [--repeat N] [--store URI]   (writes jobs.md in
                     results_dir)
"""
import argparse
import http.client
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

US = 0.0724
BASE = {"chi": 0.2, "eta": 4, "us": US, "ur": 0.6178, "V": 1}
GUESS = [9.4545, 2.23587]  # the paper's overshoot orbit's phase durations


def start(daemon, store, extra=()):
    proc = subprocess.Popen(
        [daemon, "--port", "0", "--quiet", "--job-store", store,
         "--max-seconds", "600", "--max-map-cells", "40000",
         "--map-threads", "1", "--job-workers", "1",
         "--client-workers",
         str(os.cpu_count() or 1), *extra],
        stderr=subprocess.PIPE, text=True)
    line = proc.stderr.readline()
    m = re.search(r":(\d+)", line)
    if not m:
        proc.kill()
        sys.exit("the daemon did not start: " + line)
    return proc, int(m.group(1))


def request(port, method, path, body=None, headers=None, timeout=3600):
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    h = {"Content-Type": "application/json"}
    h.update(headers or {})
    conn.request(method, path, None if body is None else json.dumps(body), h)
    resp = conn.getresponse()
    data = resp.read()
    status, hdrs = resp.status, dict(resp.getheaders())
    conn.close()
    return status, hdrs, data


def run_job(port, path, body, poll=0.05):
    """Submit, poll until finished, read the results: (seconds, bytes)."""
    t0 = time.perf_counter()
    status, hdrs, data = request(port, "POST", path, body,
                                 {"Prefer": "respond-async"})
    if status != 201:
        sys.exit("job refused: %d %s" % (status, data[:300]))
    loc = hdrs["Location"]
    while True:
        _, _, doc = request(port, "GET", loc)
        st = json.loads(doc)
        if st["status"] in ("successful", "failed", "dismissed"):
            break
        time.sleep(poll)
    if st["status"] != "successful":
        sys.exit("job %s: %s" % (st["status"], st.get("message")))
    _, _, res = request(port, "GET", loc + "/results")
    return time.perf_counter() - t0, res


def cpu_seconds(proc):
    """The CPU time (user and system) the daemon has used so far."""
    with open("/proc/%d/stat" % proc.pid) as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def median(v):
    v = sorted(v)
    return v[len(v) // 2] if len(v) % 2 else (v[len(v) // 2 - 1] +
                                               v[len(v) // 2]) / 2


def strip_seconds(lines):
    out = []
    for ln in lines:
        o = json.loads(ln)
        o.pop("seconds", None)
        out.append(o)
    return out


def map_body(n):
    # search_every 8: what is measured is the job against the synchronous
    # map, and the lattice's searches are what a job spreads over chunks
    return {"params": BASE, "kind": "overshoot", "search_every": 8,
            "axes": [{"parameter": "chi", "from": 0.04, "to": 0.96, "n": n},
                     {"parameter": "ur", "from": US * 1.5, "to": US * 15,
                      "n": n}]}


def sweep_body(items):
    reqs = []
    for i in range(items):
        ur = 0.45 + 0.35 * i / max(items - 1, 1)
        p = dict(BASE, ur=ur)
        reqs.append({"id": i, "path": "/orbit",
                     "body": {"params": p, "kind": "overshoot",
                              "guess": {"durations": GUESS}}})
    return {"requests": reqs}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("daemon")
    ap.add_argument("results", nargs="?")
    ap.add_argument("--cells", type=int, default=200)
    ap.add_argument("--items", type=int, default=100000)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--store")
    a = ap.parse_args()
    rows = []
    tmp = tempfile.mkdtemp()
    try:
        for replicas in (1, 2):
            store = a.store or "sqlite:%s/jobs-%d.sqlite" % (tmp, replicas)
            procs = [start(a.daemon, store) for _ in range(replicas)]
            port = procs[0][1]
            try:
                body = map_body(a.cells)
                proc = procs[0][0]
                sync_s, sync_c, job_s, job_c, same = [], [], [], [], True
                for _ in range(a.repeat if replicas == 1 else 1):
                    if replicas == 1:
                        c0, t0 = cpu_seconds(proc), time.perf_counter()
                        st, _, sync = request(port, "POST", "/map", body)
                        sync_s.append(time.perf_counter() - t0)
                        sync_c.append(cpu_seconds(proc) - c0)
                        if st != 200:
                            sys.exit("sync map: %d %s" % (st, sync[:300]))
                        sync_lines = strip_seconds(sync.decode().splitlines())
                    c0 = cpu_seconds(proc)
                    s, res = run_job(port, "/map", body)
                    job_s.append(s)
                    job_c.append(cpu_seconds(proc) - c0)
                    same = same and strip_seconds(
                        res.decode().splitlines()) == sync_lines
                rows.append(("%dx%d /map" % (a.cells, a.cells), replicas,
                             median(sync_s) if sync_s else None,
                             median(job_s), same,
                             (median(sync_c), median(job_c))
                             if replicas == 1 else None))
                body = sweep_body(a.items)
                job_s, res = run_job(port, "/batch", body)
                lines = res.decode().splitlines()
                ok = json.loads(lines[-1]).get("ok")
                rows.append(("%d /orbit items (guess)" % a.items, replicas,
                             None, job_s, ok == a.items, None))
            finally:
                for p, _ in procs:
                    p.terminate()
                    p.wait()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    out = ["| work | replicas | synchronous (s) | job (s) | job / sync, or "
           "rate | answer |", "| --- | ---: | ---: | ---: | ---: | --- |"]
    cpu = []
    for work, rep, s, j, same, c in rows:
        if c:
            cpu.append("%s: the daemon's CPU %.2f s synchronously, %.2f s as "
                       "a job (%.3f)" % (work, c[0], c[1], c[1] / c[0]))
        ratio = "%.3f" % (j / s) if s else ""
        if "items" in work:
            ratio = "%.0f items/s" % (a.items / j)
        out.append("| %s | %d | %s | %.2f | %s | %s |" % (
            work, rep, "%.2f" % s if s else "", j, ratio,
            "same" if same else "DIFFERS"))
    text = "\n".join(out) + "\n"
    if a.repeat > 1:
        text += "\nMedians of %d runs each, in turn.\n" % a.repeat
    text += "".join("\n" + c + "\n" for c in cpu)
    print(text)
    if a.results:
        with open(os.path.join(a.results, "jobs.md"), "w") as f:
            f.write("# Jobs against synchronous answers (bench/jobs.py)\n\n"
                    + text)


if __name__ == "__main__":
    main()
