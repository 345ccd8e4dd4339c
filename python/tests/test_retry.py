"""503 retried after its Retry-After, provoked honestly: a daemon with one
worker and a queue of one per client, kept busy by two slow /basins (one
running, one waiting), so that a third request is refused at once.  The
delay each 503 names, from a fake server (the daemon always names 1 s);
network errors, retried on idempotent calls only."""

from __future__ import annotations

import json
import socket
import threading
import time
from typing import Any, Callable, List, Optional, Tuple, Type

import pytest

import stickslip
from conftest import PAPER, Daemon
from fake import FakeServer
from proxy import listen, read_request

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
    slept.clear()
    with pytest.raises(stickslip.TransportError):
        c.submit("/orbit", params=PAPER)
    assert slept == [0.1, 0.2, 0.4]


OVERLOADED = json.dumps({"type": "/problems/overloaded", "status": 503,
                         "title": "Service Unavailable",
                         "detail": "every compute slot stayed busy",
                         "request_id": "0123456789abcdef"}).encode()


def refusals(*delays: Optional[str]) -> Callable[[Any], Any]:
    """A route answering 503 with each Retry-After of ``delays`` in turn
    (None: no header), then 200."""
    left = list(delays)

    def route(_: Any) -> Any:
        if not left:
            return {"status": "ok"}
        delay = left.pop(0)
        headers = {"Content-Type": "application/problem+json"}
        if delay is not None:
            headers["Retry-After"] = delay
        return (503, headers, OVERLOADED)
    return route


def test_503_waits_the_headers_delay() -> None:
    """The delay slept is the one each 503 names (capped at 30 s), as many
    times as the retries allow; a 503 without Retry-After is raised."""
    cases: List[Tuple[Tuple[Optional[str], ...], int, List[float],
                      Optional[Type[stickslip.ProblemError]]]] = [
        (("2", "0.25"), 3, [2.0, 0.25], None),
        (("120",), 3, [30.0], None),
        (("1.5",) * 5, 2, [1.5, 1.5], stickslip.Overloaded),
        ((None,), 3, [], stickslip.Overloaded)]
    for delays, retries, want, raised in cases:
        with FakeServer({("GET", "/health"): refusals(*delays)}) as fake:
            c = stickslip.Client(fake.url, retries=retries)
            slept: List[float] = []
            c._t.sleep = slept.append
            if raised is None:
                assert c.health() == {"status": "ok"}
            else:
                with pytest.raises(raised) as info:
                    c.health()
                assert info.value.request_id == "0123456789abcdef"
            assert slept == want, delays
            assert len(fake.log) == len(want) + 1, delays


def test_retries_bound_the_whole_call() -> None:
    """``retries`` bounds every attempt of a call: 503s refused before the
    answer and answers cut inside their body share it (each ask again does
    not start a count of its own)."""
    served: List[int] = []

    def health(_: Any) -> Any:
        served.append(1)
        if len(served) % 2:
            return (503, {"Content-Type": "application/problem+json",
                          "Retry-After": "0"}, OVERLOADED)
        return (200, {"X-Cut": "5", "Content-Type": "application/json"},
                b'{"status":"ok"}')

    for retries in (0, 1, 2, 5):
        served.clear()
        with FakeServer({("GET", "/health"): health}) as fake:
            c = stickslip.Client(fake.url, retries=retries)
            c._t.sleep = lambda _: None
            with pytest.raises(stickslip.StickslipError):
                c.health()
            assert len(served) == retries + 1, retries


class Hangup:
    """A server that reads each request whole and closes the connection
    without answering (a daemon that died mid-request, a proxy's reset):
    the request may have been acted on.  ``requests``: how many came."""

    def __init__(self) -> None:
        self.requests = 0
        self.sock, self.url = listen(self.serve)

    def serve(self, sock: socket.socket) -> None:
        while True:
            conn, _ = sock.accept()
            read_request(conn)
            self.requests += 1
            conn.close()


def test_sent_request_retried_only_when_idempotent() -> None:
    """A connection closed after the request was sent: the computing
    calls are asked again (they have no effect but their answer); a job's
    submission is not, since the daemon may have made the job."""
    server = Hangup()
    c = stickslip.Client(server.url, retries=2)
    slept: List[float] = []
    c._t.sleep = slept.append
    with pytest.raises(stickslip.TransportError):
        c.orbit(params=PAPER, kind="overshoot")
    assert server.requests == 3 and slept == [0.1, 0.2]
    slept.clear()
    with pytest.raises(stickslip.TransportError):
        c.submit("/orbit", params=PAPER, kind="overshoot")
    assert server.requests == 4 and slept == []


def test_answer_cut_short_asked_again() -> None:
    """A JSON answer cut inside its body (the connection closed before its
    Content-Length) is asked again, as a network error is."""
    served: List[int] = []

    def health(_: Any) -> Any:
        served.append(1)
        cut = {"X-Cut": "5"} if len(served) < 3 else {}
        return (200, dict(cut, **{"Content-Type": "application/json"}),
                b'{"status":"ok"}')

    with FakeServer({("GET", "/health"): health}) as fake:
        c = stickslip.Client(fake.url, retries=2)
        slept: List[float] = []
        c._t.sleep = slept.append
        assert c.health() == {"status": "ok"}
        assert len(served) == 3 and slept == [0.1, 0.2]
        served.clear()
        c = stickslip.Client(fake.url, retries=1)
        c._t.sleep = slept.append
        with pytest.raises(stickslip.TransportError):
            c.health()
        assert len(served) == 2
