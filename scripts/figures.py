#!/usr/bin/env python3
"""The README's pictures, from a running stickslipd's answers.

  python3 scripts/figures.py [URL] [OUT_DIR]
  (default http://127.0.0.1:8080 and bench/results), against a daemon
  started with a compute limit that the 100x100 map fits in:
  stickslipd --max-seconds 120

existence_map.png: POST /map of the overshoot orbits over ur/us 1.5-15
(across) and chi 0.04-0.96 (up), eta 4, us 0.0724, V 1, 100x100 cells:
white none, light grey unstable, dark grey stable, black two or more.
basins.png: POST /basins of the paper's set over x1 in [-2, 4] (across)
and x2 in [0, 8] (up) with x1' = 0, x2' = V, 256x256 cells: light the
overshoot orbit's basin, dark the period-3 orbit's, red unresolved.
Only the Python standard library is used.
"""
import base64
import json
import struct
import sys
import urllib.request
import zlib

URL = sys.argv[1] if len(sys.argv) > 1 else "http://127.0.0.1:8080"
OUT = sys.argv[2] if len(sys.argv) > 2 else "bench/results"
PAPER = {"chi": 0.2, "eta": 4, "us": 0.0724, "ur": 0.6178, "V": 1}


def post(path, body):
    req = urllib.request.Request(
        URL + path, data=json.dumps(body).encode(),
        headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=600) as r:
        return r.read().decode()


def png(path, rows, k=1):
    """rows: top to bottom, each a list of (r, g, b); each pixel k x k."""
    rows = [[px for px in row for _ in range(k)] for row in rows for _ in
            range(k)]
    h, w = len(rows), len(rows[0])
    raw = b"".join(b"\0" + bytes(c for px in row for c in px) for row in rows)

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" +
                chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def existence_map(n=100):
    us = PAPER["us"]
    text = post("/map", {
        "params": PAPER, "kind": "overshoot",
        "axes": [{"parameter": "chi", "from": 0.04, "to": 0.96, "n": n},
                 {"parameter": "ur", "from": 1.5 * us, "to": 15 * us,
                  "n": n}],
        "fields": ["stable"]})
    grid = [[(255, 255, 255)] * n for _ in range(n)]
    done = None
    for line in text.splitlines():
        cell = json.loads(line)
        if cell.get("done"):
            done = cell
            continue
        i, j = cell["index"]
        orbits = cell["orbits"]
        colour = ((255, 255, 255) if not orbits else
                  (0, 0, 0) if len(orbits) > 1 else
                  (70, 70, 70) if orbits[0]["stable"] else (190, 190, 190))
        grid[n - 1 - i][j] = colour  # chi up
    png(OUT + "/existence_map.png", grid, 3)
    return done


def basins(n=256):
    ans = json.loads(post("/basins", {
        "params": PAPER,
        "axes": [{"variable": "x1", "from": -2, "to": 4, "n": n},
                 {"variable": "x2", "from": 0, "to": 8, "n": n}],
        "state": {"v1": 0, "v2": 1}}))
    labels = base64.b64decode(ans["labels"]["data"])
    shade = {}
    for a in ans["attractors"]:
        shade[a["label"]] = ((225, 225, 225) if a["n_turns"] == 1 else
                             (40, 40, 40) if a["n_turns"] == 3 else
                             (120, 120, 200))
    rows = []
    for j in range(n - 1, -1, -1):  # x2 up
        rows.append([shade.get(labels[i * n + j], (220, 30, 30))
                     for i in range(n)])  # x1 across
    png(OUT + "/basins.png", rows)
    return ans


if __name__ == "__main__":
    done = existence_map()
    print("existence_map.png: %d cells, %d with an overshoot orbit, %.2f s" %
          (done["cells"], done["with_orbits"], done["seconds"]))
    ans = basins()
    print("basins.png: " + "; ".join(
        "%s orbit of %d turns: %.1f%%" % (a["kind"], a["n_turns"],
                                           100 * a["fraction"])
        for a in ans["attractors"]))
