#!/usr/bin/env python3
"""Two daemons on one PostgreSQL job store, one killed mid-job; and a
store that stops answering.

A /batch job of many chunks is submitted to replica A; both replicas
claim its chunks (each one's stickslip_job_chunks_total grows), and B
answers for the job too (its status, its results); then B is killed with
SIGKILL while it computes.  The job must finish on A alone (B's chunk is
claimed again once its lease lapses), with every item answered exactly
once and each item's answer the one the synchronous /batch gives.

Then a daemon reaches the store through a proxy that is frozen (it
forwards nothing, as a server that hangs): requests for a job's status and
results wait for the store, and /health must still be answered at once,
since the store is called on workers and the reader thread, never on the
I/O thread.  Once the proxy thaws, the waiting requests are answered.

Usage: check_replicas.py STICKSLIPD @URI_FILE   (the CTest fixture pg
writes URI_FILE; without it the check is skipped, 77)
"""
import json
import re
import signal
import socket
import sys
import threading
import time

import jobcheck
from jobcheck import PAPER, check, outcome, pg_uri

ITEMS = 32 * 24  # 24 chunks of 32 items and the done line


PROCS = []


def start(daemon, uri, lease="1"):
    p, port = jobcheck.start(daemon, "--job-store", uri, "--job-lease",
                             lease, "--job-workers", "1")
    PROCS.append(p)
    return p, port


def call(port, method, path, body=None, headers=None, timeout=120):
    return jobcheck.call(port, method, path, body, headers, timeout)


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


class Proxy:
    """A TCP proxy to host:port; while frozen it holds what it reads."""

    def __init__(self, host, port):
        self.up = (host, port)
        self.thawed = threading.Event()
        self.thawed.set()
        self.ls = socket.socket()
        self.ls.bind(("127.0.0.1", 0))
        self.ls.listen(16)
        self.port = self.ls.getsockname()[1]
        threading.Thread(target=self.accept, daemon=True).start()

    def accept(self):
        while True:
            a, _ = self.ls.accept()
            b = socket.create_connection(self.up)
            for src, dst in ((a, b), (b, a)):
                threading.Thread(target=self.pump, args=(src, dst),
                                 daemon=True).start()

    def pump(self, src, dst):
        try:
            while True:
                data = src.recv(65536)
                if not data:
                    break
                self.thawed.wait()
                dst.sendall(data)
        except OSError:
            pass
        for s in (src, dst):
            try:
                s.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass


def check_stalled_store(daemon, uri):
    m = re.match(r"(postgresql://[^@]*@)([^:/]+):(\d+)(/.*)$", uri)
    proxy = Proxy(m.group(2), int(m.group(3)))
    # a long lease: no renewal is due while the store hangs
    c, pc = start(daemon, "%s127.0.0.1:%d%s"
                  % (m.group(1), proxy.port, m.group(4)), lease="600")
    body = {"params": PAPER, "initial": [0.1, 0, 0, 1], "t_end": 100}
    st, hdr, _ = call(pc, "POST", "/simulate", body,
                      {"Prefer": "respond-async"})
    loc = hdr.get("Location", "")
    t0 = time.monotonic()
    while time.monotonic() - t0 < 60:
        if json.loads(call(pc, "GET", loc)[2])["status"] == "successful":
            break
        time.sleep(0.05)
    check(st == 201, "a job through the proxy (%d)" % st)
    proxy.thawed.clear()
    answers = {}

    def ask(what, path):
        answers[what] = call(pc, "GET", path)[0]

    waiting = [threading.Thread(target=ask, args=(w, p))
               for w, p in (("status", loc), ("results", loc + "/results"),
                            ("list", "/jobs"))]
    for t in waiting:
        t.start()
    time.sleep(0.5)
    worst = 0.0
    for _ in range(5):
        t0 = time.monotonic()
        try:
            ok = call(pc, "GET", "/health", timeout=3)[0] == 200
        except OSError:
            ok = False
        worst = max(worst, time.monotonic() - t0 if ok else 99)
        time.sleep(0.1)
    check(not answers and worst < 1.0,
          "/health while the store hangs under three job requests: worst "
          "%.3f s (requests answered meanwhile: %s)" % (worst, answers))
    proxy.thawed.set()
    for t in waiting:
        t.join(60)
    check(answers == {"status": 200, "results": 200, "list": 200},
          "the waiting requests answered once the store answers: %s"
          % answers)


def main():
    daemon, uri = sys.argv[1], pg_uri(sys.argv[2])
    if uri is None:
        return 77
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
        check_stalled_store(daemon, uri)
    finally:
        for p in PROCS:
            if p.poll() is None:
                p.terminate()
                p.wait()
    return outcome()


if __name__ == "__main__":
    sys.exit(main())
