"""A command line for quick looks from a shell:

    python -m stickslip [--url URL] orbit --chi 0.2 --eta 4 --us 0.0724 \\
        --ur 0.6178 --V 1 --kind overshoot [--format json|table]
    python -m stickslip simulate --chi 0.2 ... --initial X1 X2 V1 V2 \\
        --t-end 10
    python -m stickslip version | health

The daemon is ``--url``, else $STICKSLIP_URL, else http://127.0.0.1:8080.
JSON is the answer as the daemon gives it; a table shows its main fields.
A problem is printed on stderr (exit 2), an unreachable daemon too (3).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from typing import Any, Dict, List, Optional, Sequence, TextIO

from .client import Client
from .errors import ProblemError, TransportError

PARAMS = ("chi", "eta", "us", "ur", "V")


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m stickslip",
                                description="A client of stickslipd.")
    p.add_argument("--url", default=os.environ.get(
        "STICKSLIP_URL", "http://127.0.0.1:8080"))
    p.add_argument("--timeout", type=float, default=60.0)
    sub = p.add_subparsers(dest="command", required=True)
    for name, text in (("orbit", "the periodic orbits (POST /orbit)"),
                       ("simulate", "a motion (POST /simulate)")):
        s = sub.add_parser(name, help=text)
        for k in PARAMS:
            s.add_argument("--" + k, type=float, required=True)
        s.add_argument("--format", choices=("json", "table"), default="json")
    orbit = sub.choices["orbit"]
    orbit.add_argument("--kind", choices=("overshoot", "stick-slip", "other",
                                          "all"))
    orbit.add_argument("--max-period", type=int)
    sim = sub.choices["simulate"]
    sim.add_argument("--initial", type=float, nargs=4, required=True,
                     metavar=("X1", "X2", "V1", "V2"))
    sim.add_argument("--t-end", type=float, required=True)
    sim.add_argument("--samples", type=int)
    sub.add_parser("version", help="GET /version")
    sub.add_parser("health", help="GET /health")
    return p


def _request(c: Client, a: argparse.Namespace) -> Dict[str, Any]:
    if a.command in ("version", "health"):
        answer: Dict[str, Any] = getattr(c, a.command)()
        return answer
    body: Dict[str, Any] = {"params": {k: getattr(a, k) for k in PARAMS}}
    if a.command == "orbit":
        if a.kind:
            body["kind"] = a.kind
        if a.max_period:
            body["max_period"] = a.max_period
        return c.orbit(body)
    body.update(initial=a.initial, t_end=a.t_end)
    if a.samples:
        body["samples"] = {"n": a.samples}
    return c.simulate(body)


def _table(rows: List[List[str]], out: TextIO) -> None:
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    for r in rows:
        out.write("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip()
                  + "\n")


def _orbit_table(answer: Dict[str, Any], out: TextIO) -> None:
    rows = [["kind", "period", "spectral_radius", "stable", "min_margin",
             "phases"]]
    for o in answer["orbits"]:
        st = o["stability"]
        rows.append([o["kind"], "%.6f" % o["period"],
                     "%.6f" % st["spectral_radius"],
                     "yes" if st["stable"] else "no",
                     "%.6g" % o["margins"]["min"]["value"],
                     ", ".join("%s %.6f" % (p["mode"], p["duration"])
                               for p in o["phases"])])
    _table(rows, out)
    if not answer["orbits"]:
        out.write("no orbit: %s\n" % answer.get("reason", ""))


def _simulate_table(answer: Dict[str, Any], out: TextIO) -> None:
    rows = [["t", "from", "to", "x1", "x2", "v1", "v2"]]
    for e in answer.get("events", []):
        rows.append(["%.6f" % e["t"], e["from"], e["to"]] +
                    ["%.6f" % v for v in e["x"]])
    f = answer["final"]
    rows.append(["%.6f" % f["t"], f["mode"], "(final)"] +
                ["%.6f" % v for v in f["x"]])
    _table(rows, out)


def main(argv: Optional[Sequence[str]] = None,
         out: Optional[TextIO] = None) -> int:
    a = _parser().parse_args(argv)
    out = out or sys.stdout
    try:
        answer = _request(Client(a.url, timeout=a.timeout), a)
    except ProblemError as e:
        sys.stderr.write("stickslip: %s\n" % e)
        return 2
    except TransportError as e:
        sys.stderr.write("stickslip: %s\n" % e)
        return 3
    if getattr(a, "format", "json") == "table" and a.command == "orbit":
        _orbit_table(answer, out)
    elif getattr(a, "format", "json") == "table":
        _simulate_table(answer, out)
    else:
        out.write(json.dumps(answer) + "\n")
    return 0
