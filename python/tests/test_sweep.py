"""Sweeps through /batch: results in the items' order, under the daemon's
limits, interrupted and resumed with no item computed twice (counted at the
daemon by stickslip_batch_items_total), a torn journal, 503 lines sent
again."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from typing import Any, Callable, Dict, List

import stickslip
from conftest import HERE, PAPER, Daemon
from fake import FakeServer


def items(n: int) -> List[Dict[str, Any]]:
    return [{"params": dict(PAPER, ur=0.45 + 0.005 * i), "kind": "all"}
            for i in range(n)]


def computed(d: Daemon) -> float:
    return d.metric("stickslip_batch_items_total", endpoint="orbit")


def test_results_in_order_under_limits(start: Callable[..., Daemon],
                                       client: stickslip.Client) -> None:
    d = start("--max-batch-items", "4", "--max-body", "1200")
    named = [{"id": "p%d" % i, "body": b} for i, b in enumerate(items(11))]
    got = d.client().sweep(named)
    assert [r["id"] for r in got] == ["p%d" % i for i in range(11)]
    for r, b in zip(got, items(11)):
        assert r["status"] == 200
        assert r["body"]["orbits"] == client.orbit(b)["orbits"]
    # each item computed once, in batches the daemon took
    assert computed(d) == 11
    assert d.metric("stickslip_requests_total", endpoint="batch",
                    code="200") >= 3


def test_problem_items_are_results(client: stickslip.Client) -> None:
    got = client.sweep([{"params": PAPER, "kind": "overshoot"},
                        {"params": dict(PAPER, chi=-1)}])
    assert [r["id"] for r in got] == [0, 1]
    assert got[0]["status"] == 200 and got[1]["status"] == 422
    assert got[1]["body"]["pointer"] == "/body/params/chi"


SCRIPT = """
import sys, json
sys.path.insert(0, %r)
import stickslip
items = json.load(open(sys.argv[2]))
stickslip.Client(sys.argv[1]).sweep(items, journal=sys.argv[3])
"""


def test_interrupted_and_resumed(start: Callable[..., Daemon],
                                 tmp_path: Any) -> None:
    d = start("--batch-parallel", "1")
    todo = items(60)
    (tmp_path / "items.json").write_text(json.dumps(todo))
    journal = str(tmp_path / "sweep.jsonl")
    proc = subprocess.Popen([sys.executable, "-c",
                             SCRIPT % os.path.dirname(HERE), d.url,
                             str(tmp_path / "items.json"), journal])
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if os.path.exists(journal) and \
                open(journal).read().count("\n") >= 11:
            break
        time.sleep(0.005)
    proc.kill()
    proc.wait()
    with open(journal, "a") as f:
        f.write('{"id": 59, "status": 2')  # a torn last line
    kept = open(journal).read().count("\n") - 1
    assert 10 <= kept < 60
    time.sleep(0.5)  # the items in flight at the kill are done or cancelled
    first = computed(d)
    got = d.client().sweep(todo, journal=journal)
    # the second run computed exactly the items the journal lacked
    assert computed(d) - first == 60 - kept
    assert [r["id"] for r in got] == list(range(60))
    assert all(r["status"] == 200 for r in got)
    lines = open(journal).read().splitlines()
    assert len(lines) == 61 and json.loads(lines[0])["path"] == "/orbit"
    # a third run computes nothing; a changed body is computed again
    again = d.client().sweep(todo, journal=journal)
    assert again == got and computed(d) - first == 60 - kept
    todo[5] = dict(todo[5], kind="overshoot")
    d.client().sweep(todo, journal=journal)
    assert computed(d) - first == 60 - kept + 1


def test_503_lines_sent_again(monkeypatch: Any) -> None:
    """A batch whose second item is answered 503 (the daemon's queue full
    with none of the batch in flight; provoked here by a fake server in the
    test process, which answers each item's line itself)."""
    seen: List[List[Any]] = []

    def batch(body: Dict[str, Any]) -> List[Dict[str, Any]]:
        reqs = body["requests"]
        seen.append([r["body"]["n"] for r in reqs])
        lines = []
        for i, r in enumerate(reqs):
            busy = r["body"]["n"] == 1 and len(seen) == 1
            lines.append({"id": None, "index": i,
                          "status": 503 if busy else 200,
                          "body": {"type": "/problems/overloaded"} if busy
                          else {"twice": 2 * r["body"]["n"]}})
        return lines + [{"done": True}]

    with FakeServer({("POST", "/batch"): batch}) as fake:
        monkeypatch.setattr("stickslip.sweep.RETRY_DELAY", 0.01)
        got = stickslip.Client(fake.url).sweep(
            [{"n": i} for i in range(3)], path="/x")
    assert seen == [[0, 1, 2], [1]]
    assert [r["body"]["twice"] for r in got] == [0, 2, 4]
