#!/usr/bin/env python3
"""A /map job and a /basins job in its NDJSON form against the synchronous
answers, over HTTP, on one job store.

  check_job_answers.py STICKSLIPD STORE

STORE is a job store URI (sqlite:PATH), or @FILE naming the file the CTest
fixture pg writes a PostgreSQL URI to: the check then works in a database
of its own, made with psql and dropped after (skipped, 77, without the
file).

- /map: the job's results are the synchronous /map's cells, cell by cell
  (each line equal as JSON, in the same order), and its done line but for
  "seconds" (a job's is its compute time).
- /basins with Accept: application/x-ndjson: the job's results are the
  synchronous NDJSON answer byte for byte (it reports no time); while the
  job runs, ?wait=false gives the head and rows' lines already stored and
  no last line, and the job's items done count those rows.
- Each job's items, counted by the replica that stored its chunks:
  stickslip_job_items_total{endpoint} is the map's cells, then the
  basins' cells.
"""
import json
import os
import re
import subprocess
import sys
import time

from jobcheck import PAPER, call, check, outcome, pg_uri, start

# 12x12 cells: lattice groups and the chunk that spreads them
MAP = {"params": PAPER, "kind": "all",
       "axes": [{"parameter": "ur", "from": 0.45, "to": 0.9, "n": 12},
                {"parameter": "chi", "from": 0.1, "to": 0.5, "n": 12}]}
# 96 rows of 512 cells: 6 groups of 16 rows, a few tenths of a second each
BASINS = {"params": PAPER,
          "axes": [{"variable": "x1", "from": -2, "to": 4, "n": 96},
                   {"variable": "x2", "from": 0, "to": 8, "n": 512}],
          "state": {"v1": 0, "v2": 1}}
NDJSON = {"Accept": "application/x-ndjson"}


def submit(port, path, body, headers=None):
    h = {"Prefer": "respond-async"}
    h.update(headers or {})
    st, hdr, _ = call(port, "POST", path, body, h)
    check(st == 201, "%s accepted as a job (%d)" % (path, st))
    return hdr.get("Location", "")


def status(port, loc):
    return json.loads(call(port, "GET", loc)[2])


def finished(port, loc, seconds=300):
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds:
        s = status(port, loc)
        if s["status"] not in ("accepted", "running"):
            return s
        time.sleep(0.05)
    return status(port, loc)


def job_items(port, endpoint):
    _, _, text = call(port, "GET", "/metrics")
    m = re.search(r'^stickslip_job_items_total\{endpoint="%s"\} (\d+)'
                  % endpoint, text, re.M)
    return int(m.group(1)) if m else 0


def check_map(port):
    loc = submit(port, "/map", MAP)
    s = finished(port, loc)
    check(s["status"] == "successful", "the map job succeeds")
    _, _, got = call(port, "GET", loc + "/results")
    _, _, want = call(port, "POST", "/map", MAP)
    got, want = got.splitlines(), want.splitlines()
    cells = 144
    check(len(got) == len(want) == cells + 1,
          "%d lines from the job, %d from the request" % (len(got),
                                                         len(want)))
    same = sum(1 for g, w in zip(got[:cells], want[:cells])
               if json.loads(g) == json.loads(w))
    check(same == cells, "the job's cells are the request's, cell by cell "
          "(%d of %d equal)" % (same, cells))
    gd, wd = json.loads(got[-1]), json.loads(want[-1])
    gd.pop("seconds", None)
    wd.pop("seconds", None)
    check(gd == wd, "the done lines are the same but for their seconds")
    n = job_items(port, "map")
    check(n == cells, "the job's %d items counted (%d)" % (cells, n))


def check_basins(port):
    loc = submit(port, "/basins", BASINS, NDJSON)
    s = status(port, loc)
    check(s["path"] == "/basins?f=ndjson" and s["processID"] == "basins",
          "the job keeps its form (%s, %s)" % (s["path"], s["processID"]))
    # the rows' lines while the job runs
    part, done, t0 = "", 0, time.monotonic()
    while time.monotonic() - t0 < 300:
        s = status(port, loc)
        if s["status"] != "running" and s["status"] != "accepted":
            break
        done = s["items"]["done"]
        if done >= 2 * 16 * 512:
            _, _, part = call(port, "GET", loc + "/results?wait=false")
            break
        time.sleep(0.02)
    lines = [json.loads(x) for x in part.splitlines()]
    rows = [x for x in lines if "row" in x]
    check(len(lines) >= 3 and "attractors" in lines[0] and
          not any(x.get("done") for x in lines) and
          sum(x["rows"] for x in rows) * 512 >= done,
          "while it runs: the head and %d rows' lines of %d cells done, "
          "no last line" % (len(rows), done))
    s = finished(port, loc)
    check(s["status"] == "successful", "the basins job succeeds")
    st, hdr, got = call(port, "GET", loc + "/results")
    _, whdr, want = call(port, "POST", "/basins", BASINS, NDJSON)
    check(hdr.get("Content-Type") == whdr.get("Content-Type") ==
          "application/x-ndjson", "both answer application/x-ndjson")
    check(st == 200 and got == want and got.count("\n") == 8,
          "the job's results are the request's NDJSON byte for byte "
          "(%d lines, %d bytes)" % (got.count("\n"), len(got)))
    n = job_items(port, "basins")
    check(n == 96 * 512, "the job's %d items counted (%d)" % (96 * 512, n))
    # the JSON form stays the default
    _, jhdr, _ = call(port, "POST", "/basins", BASINS)
    check(jhdr.get("Content-Type") == "application/json",
          "without Accept: JSON")


def database(uri, name, create):
    base = re.sub(r"/[^/?]*(\?|$)", r"/postgres\1", uri.split("://", 1)[1])
    sql = "CREATE DATABASE %s" % name if create else \
        "DROP DATABASE IF EXISTS %s WITH (FORCE)" % name
    subprocess.run(["psql", "-q", uri.split("://", 1)[0] + "://" + base,
                    "-c", sql], check=create)
    return re.sub(r"/postgres(\?|$)", "/%s\\1" % name, uri)


def main():
    daemon, store = sys.argv[1], sys.argv[2]
    name = None
    if store.startswith("@"):
        uri = pg_uri(store)
        if uri is None:
            return 77
        name = "ss_job_answers_%d" % os.getpid()
        store = database(uri, name, True)
    # the synchronous answers of a daemon built with the sanitizers take
    # longer than the default --max-seconds
    p, port = start(daemon, "--job-store", store, "--job-workers", "1",
                    "--max-seconds", "300")
    try:
        check_map(port)
        check_basins(port)
    finally:
        p.terminate()
        p.wait()
        if name:
            database(uri, name, False)
    return outcome()


if __name__ == "__main__":
    sys.exit(main())
