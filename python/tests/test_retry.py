"""503 retried after its Retry-After, provoked honestly: a daemon with one
worker and a queue of one per client, kept busy by two slow /basins (one
running, one waiting), so that a third request is refused at once."""

from __future__ import annotations

import threading
import time
from typing import Callable, List

import pytest

import stickslip
from conftest import PAPER, Daemon

SLOW = {"params": PAPER, "state": {"v1": 0, "v2": 1},
        "axes": [{"variable": "x1", "from": -2, "to": 4, "n": 140},
                 {"variable": "x2", "from": 0, "to": 8, "n": 140}]}


def busy(d: Daemon) -> List[threading.Thread]:
    threads = [threading.Thread(target=d.client(retries=0).basins,
                                kwargs=SLOW) for _ in range(2)]
    for t in threads:
        t.start()
        time.sleep(0.1)
    deadline = time.monotonic() + 5
    while d.metric("stickslip_queued") < 1 and time.monotonic() < deadline:
        time.sleep(0.01)
    return threads


def test_503_raised_without_retries(start: Callable[..., Daemon]) -> None:
    d = start("--workers", "1", "--client-queue", "1")
    threads = busy(d)
    try:
        with pytest.raises(stickslip.Overloaded) as info:
            d.client(retries=0).orbit(params=PAPER, kind="overshoot")
        e = info.value
        assert isinstance(e, stickslip.Unavailable)
        assert e.status == 503 and e.kind == "overloaded"
        assert e.retry_after == 1.0 and e.request_id
    finally:
        for t in threads:
            t.join()


def test_503_retried(start: Callable[..., Daemon]) -> None:
    d = start("--workers", "1", "--client-queue", "1")
    threads = busy(d)
    t0 = time.monotonic()
    try:
        ans = d.client(retries=10).orbit(params=PAPER, kind="overshoot")
    finally:
        for t in threads:
            t.join()
    assert abs(ans["orbits"][0]["period"] - 10.271429855353585) < 1e-9
    # refused at least once, then answered after Retry-After's second
    assert d.metric("stickslip_requests_total", endpoint="orbit",
                    code="503") >= 1
    assert time.monotonic() - t0 >= 1.0
    assert d.metric("stickslip_requests_total", endpoint="orbit",
                    code="200") == 1


def test_network_errors_retried_on_idempotent_calls_only() -> None:
    """Nothing listens on the port: refused connections are retried (each
    retry sleeps), for a job's submission too since nothing was sent."""
    import socket
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    c = stickslip.Client("http://127.0.0.1:%d" % port, retries=3)
    slept: List[float] = []
    c._t.sleep = slept.append
    with pytest.raises(stickslip.TransportError):
        c.health()
    assert slept == [0.1, 0.2, 0.4]
