"""Streams cut mid-way: a proxy in the test process forwards to the live
daemon and cuts the first answer after its first lines; the client asks
again for what is missing and yields every line once."""

from __future__ import annotations

import json

import stickslip
from conftest import PAPER, Daemon
from proxy import CuttingProxy


def test_batch_cut_resumed(daemon: Daemon) -> None:
    proxy = CuttingProxy(daemon.url, keep=3)
    reqs = [{"id": i, "path": "/orbit",
             "body": {"params": dict(PAPER, ur=0.62 + 0.01 * i),
                      "kind": "overshoot"}} for i in range(8)]
    lines = stickslip.Client(proxy.url).batch(reqs)
    got = list(lines)
    assert sorted(x["index"] for x in got) == list(range(8))
    assert [x["id"] for x in got] == [x["index"] for x in got]
    assert lines.done is not None and lines.done["ok"] == 8
    # the second request asked only for the five items whose lines had not
    # come, and each line is the answer to its own item
    assert len(proxy.requests) == 2
    again = json.loads(proxy.requests[1])["requests"]
    assert len(again) == 5
    seen = {x["id"] for x in got[:3]}
    assert {r["id"] for r in again} == set(range(8)) - seen
    whole = daemon.client().batch(reqs).gather()
    assert [x["body"]["orbits"] for x in sorted(got, key=lambda x: x["index"])
            ] == [x["body"]["orbits"] for x in whole]


def test_map_cut_resumed(daemon: Daemon) -> None:
    proxy = CuttingProxy(daemon.url, keep=2)
    body = {"params": PAPER, "fields": ["period"],
            "axes": [{"parameter": "ur", "from": 0.5, "to": 0.8, "n": 5}]}
    lines = stickslip.Client(proxy.url).map(body)
    got = list(lines)
    assert [x["index"] for x in got] == [[i] for i in range(5)]
    assert got == daemon.client().map(body).gather()
    assert lines.done is not None and lines.done["cells"] == 5
    assert len(proxy.requests) == 2
