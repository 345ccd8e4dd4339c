"""Every method of the client against the daemon's own answers to the same
requests sent with urllib (compared whole, but for the compute times)."""

from __future__ import annotations

import json
import urllib.request
from typing import Any, Dict, List

import stickslip
from conftest import PAPER, Daemon

VOLATILE = {"seconds", "uptime_seconds", "in_flight", "request_id"}


def clean(v: Any) -> Any:
    if isinstance(v, dict):
        return {k: clean(x) for k, x in v.items() if k not in VOLATILE}
    if isinstance(v, list):
        return [clean(x) for x in v]
    return v


def raw(d: Daemon, path: str, body: Any = None) -> str:
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(d.url + path, data=data,
                                 headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=60) as r:
        return str(r.read().decode())


def raw_lines(d: Daemon, path: str, body: Any) -> List[Dict[str, Any]]:
    return [json.loads(x) for x in raw(d, path, body).splitlines() if x]


ORBIT = {"params": PAPER, "kind": "overshoot", "samples": 20}
GUESS = {"durations": [4.4975, 2.7227, 3.0513]}


def test_get(daemon: Daemon, client: stickslip.Client) -> None:
    assert client.health() == clean(json.loads(raw(daemon, "/health"))) \
        or clean(client.health()) == clean(json.loads(raw(daemon, "/health")))
    assert client.version() == json.loads(raw(daemon, "/version"))
    assert "stickslip_requests_total" in client.metrics()


def test_orbit_keywords_and_dict(daemon: Daemon,
                                 client: stickslip.Client) -> None:
    want = clean(json.loads(raw(daemon, "/orbit", ORBIT)))
    assert clean(client.orbit(**ORBIT)) == want
    assert clean(client.orbit(ORBIT)) == want
    # the keywords win over the dict's fields
    assert clean(client.orbit(dict(ORBIT, kind="all"), kind="overshoot")) \
        == want


def test_simulate_stability_continue_basins(daemon: Daemon,
                                            client: stickslip.Client) -> None:
    orbit = client.orbit(params=PAPER, kind="overshoot")["orbits"][0]
    cases = [
        ("/simulate", client.simulate,
         {"params": PAPER, "orbit": orbit, "t_end": 30,
          "samples": {"n": 50}}),
        ("/stability", client.stability, {"params": PAPER, "orbit": orbit}),
        ("/continue", client.continuation,
         {"params": PAPER, "guess": GUESS, "parameter": "ur",
          "range": [0.5, 0.8]}),
        ("/basins", client.basins,
         {"params": PAPER, "state": {"v1": 0, "v2": 1},
          "axes": [{"variable": "x1", "from": -2, "to": 4, "n": 6},
                   {"variable": "x2", "from": 0, "to": 8, "n": 5}]}),
    ]
    for path, method, body in cases:
        assert clean(method(**body)) == clean(json.loads(raw(daemon, path,
                                                             body))), path


def test_map_lines(daemon: Daemon, client: stickslip.Client) -> None:
    body = {"params": PAPER, "fields": ["kind", "period", "stable"],
            "axes": [{"parameter": "ur", "from": 0.4, "to": 0.8, "n": 3},
                     {"parameter": "chi", "from": 0.15, "to": 0.25, "n": 2}]}
    want = raw_lines(daemon, "/map", body)
    lines = client.map(**body)
    got = list(lines)
    assert got == want[:-1]
    assert lines.done is not None and clean(lines.done) == clean(want[-1])
    assert client.map(body).gather() == want[:-1]


def test_batch_lines(daemon: Daemon, client: stickslip.Client) -> None:
    reqs = [{"id": "o%d" % i, "path": "/orbit",
             "body": {"params": dict(PAPER, ur=0.6 + 0.02 * i),
                      "kind": "overshoot"}} for i in range(6)]
    reqs.append({"id": None, "path": "/health", "body": {}})
    want = sorted(raw_lines(daemon, "/batch", {"requests": reqs})[:-1],
                  key=lambda x: x["index"])
    lines = client.batch(reqs)
    got = lines.gather()
    assert clean(got) == clean(want)
    assert [x["id"] for x in got] == [r["id"] for r in reqs]
    assert lines.done is not None and lines.done["ok"] == 6 \
        and lines.done["failed"] == 1
    assert clean(client.batch(requests=reqs).gather()) == clean(want)
