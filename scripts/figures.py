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
Each with its axes, ticks, units and a legend, drawn by matplotlib
(Debian's python3-matplotlib; scripts/setup.sh --test installs it).
"""
import base64
import json
import sys
import urllib.request

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch
except ImportError:
    sys.exit("figures.py needs matplotlib: apt-get install python3-matplotlib")

URL = sys.argv[1] if len(sys.argv) > 1 else "http://127.0.0.1:8080"
OUT = sys.argv[2] if len(sys.argv) > 2 else "bench/results"
PAPER = {"chi": 0.2, "eta": 4, "us": 0.0724, "ur": 0.6178, "V": 1}


def post(path, body):
    req = urllib.request.Request(
        URL + path, data=json.dumps(body).encode(),
        headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=600) as r:
        return r.read().decode()


def picture(path, grid, colours, names, extent, xlabel, ylabel, title):
    """grid: rows bottom to top of indices into colours; a legend of the
    indices present, named by names."""
    fig, ax = plt.subplots(figsize=(6.4, 4.8), dpi=110)
    ax.imshow(grid, origin="lower", extent=extent, aspect="auto",
              interpolation="nearest", cmap=ListedColormap(colours),
              vmin=0, vmax=len(colours) - 1)
    present = sorted({k for row in grid for k in row})
    ax.legend(handles=[Patch(facecolor=colours[k], edgecolor="0.5",
                             label=names[k]) for k in present],
              loc="upper left", bbox_to_anchor=(1.01, 1), borderaxespad=0,
              frameon=False)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)


def existence_map(n=100):
    us = PAPER["us"]
    text = post("/map", {
        "params": PAPER, "kind": "overshoot",
        "axes": [{"parameter": "chi", "from": 0.04, "to": 0.96, "n": n},
                 {"parameter": "ur", "from": 1.5 * us, "to": 15 * us,
                  "n": n}],
        "fields": ["stable"]})
    grid = [[0] * n for _ in range(n)]
    done = None
    for line in text.splitlines():
        cell = json.loads(line)
        if cell.get("done"):
            done = cell
            continue
        i, j = cell["index"]
        orbits = cell["orbits"]
        grid[i][j] = (0 if not orbits else 3 if len(orbits) > 1 else
                      2 if orbits[0]["stable"] else 1)  # row i: chi, up
    h, w = 0.92 / (2 * (n - 1)), 13.5 / (2 * (n - 1))
    picture(OUT + "/existence_map.png", grid,
            ["#ffffff", "#bebebe", "#464646", "#000000"],
            ["no overshoot orbit", "unstable", "stable", "two or more"],
            [1.5 - w, 15 + w, 0.04 - h, 0.96 + h], "ur / us (dimensionless)",
            "chi (dimensionless)",
            "overshoot orbits of period 1: eta 4, us 0.0724, V 1")
    return done


def basins(n=256):
    ans = json.loads(post("/basins", {
        "params": PAPER,
        "axes": [{"variable": "x1", "from": -2, "to": 4, "n": n},
                 {"variable": "x2", "from": 0, "to": 8, "n": n}],
        "state": {"v1": 0, "v2": 1}}))
    labels = base64.b64decode(ans["labels"]["data"])
    colours = ["#dc1e1e"]
    names = ["unresolved"]
    index = {}
    for a in ans["attractors"]:
        index[a["label"]] = len(colours)
        colours.append("#e1e1e1" if a["n_turns"] == 1 else
                       "#282828" if a["n_turns"] == 3 else "#7878c8")
        names.append("%s, %d turn%s, T = %.4f: %.1f %%" % (
            a["kind"], a["n_turns"], "s" if a["n_turns"] > 1 else "",
            a["period"], 100 * a["fraction"]))
    # row j of the picture: x2, up; column i: x1, across
    grid = [[index.get(labels[i * n + j], 0) for i in range(n)]
            for j in range(n)]
    h, w = 8 / (2 * (n - 1)), 6 / (2 * (n - 1))
    picture(OUT + "/basins.png", grid, colours, names,
            [-2 - w, 4 + w, -h, 8 + h], "x1 (dimensionless)",
            "x2 (dimensionless)",
            "basins of the paper's set, x1' = 0, x2' = V = 1")
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
