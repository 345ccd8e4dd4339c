"""python -m stickslip: its JSON is the daemon's answer, its table the
answer's fields, a problem on stderr with exit status 2."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import stickslip
from conftest import HERE, PAPER, Daemon

ARGS = ["--chi", "0.2", "--eta", "4", "--us", "0.0724", "--ur", "0.6178",
        "--V", "1"]


def run(daemon: Daemon, *args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, PYTHONPATH=os.path.dirname(HERE),
               STICKSLIP_URL=daemon.url)
    return subprocess.run([sys.executable, "-m", "stickslip", *args],
                          env=env, capture_output=True, text=True,
                          timeout=60)


def test_orbit_json(daemon: Daemon, client: stickslip.Client) -> None:
    out = run(daemon, "orbit", *ARGS, "--kind", "overshoot")
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    want = client.orbit(params=PAPER, kind="overshoot")
    assert got["orbits"] == want["orbits"] and got["input"] == want["input"]


def test_orbit_table(daemon: Daemon) -> None:
    out = run(daemon, "orbit", *ARGS, "--kind", "overshoot", "--format",
              "table")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0].split() == ["kind", "period", "spectral_radius",
                                "stable", "min_margin", "phases"]
    assert lines[1].split()[:5] == ["overshoot", "10.271430", "0.195452",
                                    "yes", "0.00065178"]
    assert lines[1].endswith("slip 4.497497, overshoot 2.722666, "
                             "stick 3.051267")


def test_simulate_table(daemon: Daemon) -> None:
    out = run(daemon, "simulate", *ARGS, "--initial", "1.2739277342427062",
              "4.362927734242709", "-0.8074871367243069", "1", "--t-end",
              "10.3", "--format", "table")
    assert out.returncode == 0, out.stderr
    rows = [line.split() for line in out.stdout.splitlines()]
    assert [r[1:3] for r in rows[1:]] == [["slip", "overshoot"],
                                          ["overshoot", "stick"],
                                          ["stick", "slip"],
                                          ["slip", "(final)"]]
    assert rows[-1][0] == "10.300000" and rows[-1][3] == "1.250698"


def test_problem(daemon: Daemon) -> None:
    out = run(daemon, "orbit", *ARGS[:1], "2", *ARGS[2:])
    assert out.returncode == 2 and out.stdout == ""
    assert "422 /problems/invalid-value" in out.stderr
    assert "/params/chi" in out.stderr
