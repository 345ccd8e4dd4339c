#!/usr/bin/env python3
"""POST /map against the same map as separate POST /orbit requests, over HTTP.

The 50x50 existence map of the overshoot orbits (ur/us 1.5-15 and chi
0.04-0.96, eta 4, us 0.0724, V 1): one /map request with the defaults (the
full search at every cell) and one with search_every 8 (its NDJSON read to
the end; median of 3 each), then the 2500 /orbit requests of its cells sent
one after another on 2 keep-alive connections, in one run.  All on a
stickslipd the script starts (port 0, one client allowed as many
computations at once as there are cores, as bench/load.sh does: by default
one client gets one core less; --max-seconds 120, for the default map takes
about as long as the separate requests, over the default 10 s).  The /orbit requests skip the finite-difference Jacobian, which the
map does not compute either.  Reports the wall times, the ratio and whether
the map holds every orbit the separate requests return.

Usage: bench/map_http.py STICKSLIPD [results_dir]   (writes map_http.md there)
"""
import http.client
import json
import os
import re
import subprocess
import sys
import threading
import time

N = 50
US = 0.0724
BASE = {"chi": 0.2, "eta": 4, "us": US, "ur": 0.6178, "V": 1}
AXES = [{"parameter": "chi", "from": 0.04, "to": 0.96, "n": N},
        {"parameter": "ur", "from": US * 1.5, "to": US * 15, "n": N}]


def value(axis, i):
    # the map's own rule: exact at both ends
    k = axis["n"] - 1
    return (axis["from"] * (k - i) + axis["to"] * i) / k


def post(conn, path, body):
    conn.request("POST", path, json.dumps(body),
                 {"Content-Type": "application/json"})
    resp = conn.getresponse()
    return resp.status, resp.read().decode()


def same(a, b):
    return (len(a["durations"]) == len(b["durations"]) and
            abs(a["period"] - b["period"]) < 1e-6 * a["period"] and
            abs(a["durations"][0] - b["durations"][0]) < 1e-6 * a["period"])


def main():
    daemon = sys.argv[1]
    outdir = sys.argv[2] if len(sys.argv) > 2 else None
    cores = str(os.cpu_count() or 1)
    proc = subprocess.Popen([daemon, "--port", "0", "--quiet",
                             "--client-workers", cores,
                             "--max-seconds", "120"],
                            stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stderr.readline()
        port = int(re.search(r":(\d+)", line).group(1))
        maps = []  # (name, median time, cells, done line)
        for name, extra in (("one `/map`, defaults (every cell)", {}),
                            ("one `/map`, `search_every` 8",
                             {"search_every": 8})):
            times = []
            for _ in range(3):
                conn = http.client.HTTPConnection("127.0.0.1", port,
                                                  timeout=600)
                t0 = time.monotonic()
                status, text = post(conn, "/map",
                                    dict({"params": BASE, "axes": AXES,
                                          "kind": "overshoot"}, **extra))
                times.append(time.monotonic() - t0)
                assert status == 200, text[:300]
                cells, done = {}, {}
                for row in text.splitlines():
                    obj = json.loads(row)
                    if "index" in obj:
                        cells[tuple(obj["index"])] = obj["orbits"]
                    elif obj.get("done"):
                        done = obj
            times.sort()
            maps.append((name, times[1], cells, done))

        todo = [(i, j) for i in range(N) for j in range(N)]
        sep, errors = {}, []
        lock = threading.Lock()

        def worker():
            conn = http.client.HTTPConnection("127.0.0.1", port, timeout=600)
            while True:
                with lock:
                    if not todo:
                        return
                    i, j = todo.pop()
                p = dict(BASE, chi=value(AXES[0], i), ur=value(AXES[1], j))
                status, text = post(conn, "/orbit",
                                    {"params": p, "kind": "overshoot",
                                     "finite_difference": False})
                if status != 200:
                    errors.append((i, j, status))
                    continue
                sep[(i, j)] = [{"period": o["period"],
                                "durations": [ph["duration"]
                                              for ph in o["phases"]]}
                               for o in json.loads(text)["orbits"]]

        t0 = time.monotonic()
        threads = [threading.Thread(target=worker) for _ in range(2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        t_sep = time.monotonic() - t0
    finally:
        proc.terminate()
        proc.wait()

    n_sep = sum(len(v) for v in sep.values())
    rows, missing_default = "", 0
    for name, t_map, cells, done in maps:
        n_map = sum(len(v) for v in cells.values())
        missing = sum(1 for c, orbits in sep.items() for o in orbits
                      if not any(same(o, q) for q in cells.get(c, [])))
        if not rows:
            missing_default = missing
        rows += "| %s | %.3f s | %d | %d | %d | %.1fx |\n" % (
            name, t_map, done["searches"], n_map, missing, t_sep / t_map)
    report = (
        "# POST /map against separate POST /orbit requests, over HTTP\n\n"
        "The 50x50 map of overshoot orbits (ur/us 1.5-15, chi 0.04-0.96, "
        "eta 4, us 0.0724, V 1) on one stickslipd, in one run of "
        "`bench/map_http.py` (`--client-workers` %s, `--max-seconds` 120): "
        "one `/map` request with its defaults and one with `search_every` 8, "
        "each read to its last line (median of 3), and the 2500 `/orbit` "
        "requests of its cells (`finite_difference` false) on 2 keep-alive "
        "connections.  \"missing\": orbits the separate requests return "
        "that the map's cell lacks.\n\n"
        "| how | wall time | full searches | orbits | missing | speed-up |\n"
        "|---|---|---|---|---|---|\n"
        "%s"
        "| 2500 `/orbit`, 2 connections | %.2f s | 2500 | %d | - | 1x |\n"
        % (cores, rows, t_sep, n_sep))
    if errors:
        report += "\n%d /orbit requests failed: %s\n" % (len(errors),
                                                        errors[:5])
    sys.stdout.write(report)
    if outdir:
        with open(os.path.join(outdir, "map_http.md"), "w") as f:
            f.write(report)
    return 0 if not errors and missing_default == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
