#!/usr/bin/env python3
"""Two daemons on one PostgreSQL job store, one killed mid-job.

A /batch job of many chunks is submitted to replica A; both replicas
claim its chunks (each one's stickslip_job_chunks_total grows), and B
answers for the job too (its status, its results); then B is killed with
SIGKILL while it computes.  The job must finish on A alone (B's chunk is
claimed again once its lease lapses), with every item answered exactly
once and each item's answer the one the synchronous /batch gives.

Usage: check_replicas.py STICKSLIPD @URI_FILE   (the CTest fixture pg
writes URI_FILE; without it the check is skipped, 77)
"""
import http.client
import json
import os
import re
import signal
import subprocess
import sys
import time

PAPER = {"chi": 0.2, "eta": 4, "us": 0.0724, "ur": 0.6178, "V": 1}
ITEMS = 32 * 24  # 24 chunks of 32 items and the done line


PROCS = []


def start(daemon, uri):
    p = subprocess.Popen(
        [daemon, "--port", "0", "--quiet", "--job-store", uri,
         "--job-lease", "1", "--job-workers", "1"],
        stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    PROCS.append(p)
    line = p.stderr.readline()
    m = re.search(r":(\d+)$", line.strip())
    if not m:
        p.kill()
        sys.exit("the daemon did not start: " + line)
    return p, int(m.group(1))


def call(port, method, path, body=None, headers=None):
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=120)
    h = {"Content-Type": "application/json"}
    h.update(headers or {})
    c.request(method, path, None if body is None else json.dumps(body), h)
    r = c.getresponse()
    data = r.read().decode()
    c.close()
    return r.status, dict(r.getheaders()), data


def chunks_done(port):
    _, _, text = call(port, "GET", "/metrics")
    m = re.search(r"^stickslip_job_chunks_total (\d+)", text, re.M)
    return int(m.group(1)) if m else -1


def canonical(lines):
    """Each item's line by its index, without the done line's seconds."""
    out, done = {}, None
    for ln in lines:
        o = json.loads(ln)
        if o.get("done"):
            o.pop("seconds", None)
            done = o
        else:
            if o["index"] in out:
                sys.exit("item %d answered twice" % o["index"])
            out[o["index"]] = o
    return out, done


def main():
    daemon, uri_arg = sys.argv[1], sys.argv[2]
    try:
        with open(uri_arg.lstrip("@")) as f:
            uri = f.read().strip()
    except OSError:
        print("no PostgreSQL (%s unreadable): skipped" % uri_arg)
        return 77
    failures = []

    def check(ok, what):
        print(("ok   " if ok else "FAIL ") + what)
        if not ok:
            failures.append(what)

    batch = {"requests": [
        {"id": i, "path": "/simulate",
         "body": {"params": PAPER, "initial": [0.1 + 1e-4 * i, 0, 0, 1],
                  "t_end": 30000, "events": False}}
        for i in range(ITEMS)]}
    try:
        a, pa = start(daemon, uri)
        b, pb = start(daemon, uri)
        st, hdr, body = call(pa, "POST", "/batch", batch,
                             {"Prefer": "respond-async"})
        check(st == 201, "the job is accepted by A (%d)" % st)
        loc = hdr.get("Location", "")
        # B knows the job A took
        st, _, body = call(pb, "GET", loc)
        check(st == 200 and json.loads(body)["path"] == "/batch",
              "B answers for A's job (%d)" % st)
        t0 = time.monotonic()
        while time.monotonic() - t0 < 60:
            if chunks_done(pa) > 0 and chunks_done(pb) > 0:
                break
            time.sleep(0.05)
        ca, cb = chunks_done(pa), chunks_done(pb)
        check(ca > 0 and cb > 0,
              "both replicas compute chunks of one job (A %d, B %d)"
              % (ca, cb))
        st, _, part = call(pb, "GET", loc + "/results?wait=false")
        check(st == 200 and part.count("\n") >= 32,
              "B streams the lines stored so far (%d lines)"
              % part.count("\n"))
        _, _, s = call(pa, "GET", loc)
        check(json.loads(s)["status"] == "running", "still running")
        b.send_signal(signal.SIGKILL)
        b.wait()
        t0 = time.monotonic()
        status = None
        while time.monotonic() - t0 < 120:
            _, _, s = call(pa, "GET", loc)
            status = json.loads(s)
            if status["status"] not in ("accepted", "running"):
                break
            time.sleep(0.1)
        check(status["status"] == "successful"
              and status["progress"] == 100,
              "the job finishes on A alone (%s)" % status["status"])
        st, _, res = call(pa, "GET", loc + "/results")
        lines = res.splitlines()
        got, done = canonical(lines)
        check(st == 200 and sorted(got) == list(range(ITEMS)),
              "every item answered once (%d of %d lines)"
              % (len(got), ITEMS))
        check(done == {"done": True, "ok": ITEMS, "failed": 0},
              "the done line counts them: %s" % done)
        # the same items answered synchronously, in one /batch
        sync = {"requests": batch["requests"][:64]}
        st, _, text = call(pa, "POST", "/batch", sync)
        want, _ = canonical(text.splitlines())
        same = all(got[i] == want[i] for i in want)
        check(st == 200 and same,
              "each item's answer is the synchronous one (first 64)")
        print("chunks: A %d, B %d (before it was killed)"
              % (chunks_done(pa), cb))
    finally:
        for p in PROCS:
            if p.poll() is None:
                p.terminate()
                p.wait()
    if failures:
        print("%d failures" % len(failures))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
