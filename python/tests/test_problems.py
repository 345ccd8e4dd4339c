"""Every problem the daemon answers is raised as its class, with the fields
of its body; the classes cover the daemon's whole table of types."""

from __future__ import annotations

import json
import os
import re
import resource
import signal
import threading
import time
from typing import Any, Callable, Dict, Tuple, Type

import pytest

import stickslip
from stickslip.errors import _BY_TYPE, problem
from conftest import PAPER, Daemon
from fake import FakeServer

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))))

CASES: Dict[str, Tuple[Type[stickslip.ProblemError], int,
                       Callable[[stickslip.Client], Any], Any]] = {
    "bad-request": (stickslip.errors.BadFraming, 400,
                    lambda c: c.request("GET", "/jobs/not-an-id"), None),
    "invalid-json": (stickslip.InvalidJSON, 400,
                     lambda c: c.request("POST", "/orbit", b'{"params":'),
                     None),
    "not-found": (stickslip.NotFound, 404,
                  lambda c: c.request("GET", "/nowhere"), None),
    "method-not-allowed": (stickslip.MethodNotAllowed, 405,
                           lambda c: c.request("GET", "/orbit"), None),
    "unsupported-media-type": (
        stickslip.UnsupportedMediaType, 415,
        lambda c: c.request("POST", "/orbit", b'{}',
                            {"Content-Type": "text/plain"}), None),
    "invalid-type": (stickslip.InvalidType, 422,
                     lambda c: c.orbit(params=dict(PAPER, eta="4")),
                     "/params/eta"),
    "invalid-value": (stickslip.InvalidValue, 422,
                      lambda c: c.orbit(params=dict(PAPER, chi=2)),
                      "/params/chi"),
    "missing-field": (stickslip.MissingField, 422,
                      lambda c: c.simulate(params=PAPER, t_end=1),
                      "/initial"),
    "unknown-field": (stickslip.UnknownField, 422,
                      lambda c: c.orbit(params=PAPER, colour="red"),
                      "/colour"),
    "limit-exceeded": (stickslip.RequestOverLimit, 422,
                       lambda c: c.orbit(params=PAPER, samples=200000),
                       "/samples"),
}


@pytest.mark.parametrize("kind", sorted(CASES))
def test_problem_raised_with_fields(client: stickslip.Client,
                                    kind: str) -> None:
    cls, status, call, pointer = CASES[kind]
    with pytest.raises(cls) as info:
        call(client)
    e = info.value
    assert type(e) is cls
    assert e.status == status and e.kind == kind
    assert e.type == "/problems/" + kind
    assert e.title and e.detail
    assert e.pointer == pointer
    assert e.request_id and re.fullmatch(r"[0-9a-f]{16}", e.request_id)
    assert e.body["detail"] == e.detail


def test_limit_named(client: stickslip.Client) -> None:
    with pytest.raises(stickslip.LimitExceeded) as info:
        client.orbit(params=PAPER, samples=200000)
    assert isinstance(info.value, stickslip.Unprocessable)
    assert info.value.limit == "max_samples"
    assert info.value.limit_value == 100000


def test_body_too_large(start: Callable[..., Daemon]) -> None:
    d = start("--max-body", "2000")
    with pytest.raises(stickslip.BodyTooLarge) as info:
        d.client().orbit(params=PAPER, guess={"durations": [1.0] * 1000})
    e = info.value
    assert isinstance(e, stickslip.ContentTooLarge) and e.status == 413
    assert e.limit == "max_body" and e.limit_value == 2000


def test_every_type_of_the_daemon_has_its_class() -> None:
    """The rows of API_PROBLEM_MAP, read from the daemon's header: each
    (type, status) is raised as a class of its own, under its status's."""
    text = open(os.path.join(ROOT, "api", "include",
                             "stickslip_api.h")).read()
    rows = re.findall(r'X\((\w+), (\d+), "([a-z-]+)", "[^"]*"\)', text)
    assert len(rows) >= 17
    by_status = {400: stickslip.BadRequest, 404: stickslip.NotFound,
                 405: stickslip.MethodNotAllowed,
                 413: stickslip.ContentTooLarge,
                 415: stickslip.UnsupportedMediaType,
                 422: stickslip.Unprocessable,
                 499: stickslip.ClientClosedRequest,
                 500: stickslip.InternalError, 503: stickslip.Unavailable}
    for _, status, kind in rows:
        e = problem({"type": "/problems/" + kind, "status": int(status),
                     "title": "t", "detail": "d"}, int(status))
        assert isinstance(e, by_status[int(status)]), kind
        assert type(e) is _BY_TYPE[(kind, int(status))], kind
        assert e.kind == kind and e.status == int(status)


def test_store_unavailable(start: Callable[..., Daemon]) -> None:
    """A job store that cannot be opened: a job is refused 503 with
    Retry-After (retried, then raised); a synchronous request is served."""
    d = start("--job-store", "sqlite:/dev/null/no/jobs.sqlite")
    c = stickslip.Client(d.url, retries=1)
    with pytest.raises(stickslip.StoreUnavailable) as info:
        c.submit("/orbit", params=PAPER, kind="overshoot")
    e = info.value
    assert isinstance(e, stickslip.Unavailable) and e.status == 503
    assert e.kind == "store-unavailable" and e.retry_after is not None
    assert c.orbit(params=PAPER, kind="overshoot")["orbits"]


def check_fields(e: stickslip.ProblemError, cls: type, status: int,
                 kind: str, pointer: Any) -> None:
    assert type(e) is cls
    assert e.status == status and e.kind == kind
    assert e.type == "/problems/" + kind
    assert e.title and e.detail
    assert e.pointer == pointer
    assert e.request_id and re.fullmatch(r"[0-9a-f]{16}", e.request_id)


def test_out_of_memory(start: Callable[..., Daemon]) -> None:
    """A daemon whose address space is capped 8 MiB above what it uses
    once started: a 2 000 000-sample motion (80 MB of samples in the
    library alone) cannot be allocated, and is answered out-of-memory; the
    daemon serves on.  The margin is wide on purpose: the worker's first
    allocations cannot reserve a malloc arena (64 MiB) under the cap, so
    each is a mapping of its own, and a margin of 1 MiB left some runs
    without room for the problem's own few hundred bytes."""
    d = start("--no-jobs", "--workers", "1", "--max-samples", "2000000")
    with open("/proc/%d/maps" % d.proc.pid) as f:
        if "libasan" in f.read():
            # AddressSanitizer reserves terabytes and aborts where an
            # allocation fails, instead of returning NULL to the daemon
            pytest.skip("a daemon built with AddressSanitizer")
    with open("/proc/%d/status" % d.proc.pid) as f:
        m = re.search(r"VmSize:\s*(\d+)", f.read())
    assert m is not None
    kib = int(m.group(1))
    cap = (kib << 10) + (8 << 20)
    resource.prlimit(d.proc.pid, resource.RLIMIT_AS, (cap, cap))
    c = d.client(retries=0)
    with pytest.raises(stickslip.ProblemError) as info:
        c.simulate(params=PAPER, initial=X0, t_end=10000,
                   samples={"n": 2000000})
    check_fields(info.value, stickslip.errors.OutOfMemory, 503,
                 "out-of-memory", "/samples")
    assert isinstance(info.value, stickslip.Unavailable)
    assert c.simulate(params=PAPER, initial=X0, t_end=10,
                      samples={"n": 10})["samples"]


# the stick -> slip point of the paper's orbit: a motion from it to
# t_end 1.5e7 keeps the one worker busy for about a second
X0 = [1.2739277342427062, 4.3629277342427093, -0.80748713672430694, 1.0]


def test_shutting_down(start: Callable[..., Daemon]) -> None:
    """SIGTERM while a request waits behind the one running: the running
    one is answered, the waiting one refused shutting-down."""
    d = start("--no-jobs", "--workers", "1", "--max-events", "100000000",
              "--max-horizon", "1e8", "--max-seconds", "600",
              "--drain", "60")
    got: Dict[str, Any] = {}

    def run(name: str) -> None:
        try:
            got[name] = d.client(retries=0).simulate(
                params=PAPER, initial=X0, t_end=1.5e7, events=False)
        except stickslip.ProblemError as e:
            got[name] = e

    ts = [threading.Thread(target=run, args=(n,))
          for n in ("running", "waiting")]
    for t in ts:
        t.start()
        time.sleep(0.1)
    os.kill(d.proc.pid, signal.SIGTERM)
    for t in ts:
        t.join(60)
    assert isinstance(got["running"], dict) and got["running"]["final"]
    e = got["waiting"]
    assert isinstance(e, stickslip.ProblemError), e
    check_fields(e, stickslip.errors.ShuttingDown, 503, "shutting-down",
                 None)
    assert d.proc.wait(30) == 0


# Problems no request can honestly provoke, answered from the fake server
# with the daemon's own bodies (server/request.c, api/src/problem.c):
# client-closed-request is written for a client that has gone and so
# never reads it; internal is a bug of the daemon; and no-convergence
# comes from iterations (an event's location, a special point of a family)
# that converge on every input found so far (an /orbit from a guess that
# does not converge answers 200 with its reason).
FAKE: Dict[str, Tuple[Type[stickslip.ProblemError], int, str, str,
                      Any]] = {
    "client-closed-request": (stickslip.errors.ClientClosedRequest, 499, "Client Closed Request",
                              "the client went away", None),
    "internal": (stickslip.errors.InternalError, 500, "Internal Server Error",
                 "no memory or no randomness for a job", None),
    "no-convergence": (stickslip.errors.NoConvergence, 422, "Unprocessable Content",
                       "the special point at 0.61 was not converged",
                       "/special"),
}


@pytest.mark.parametrize("kind", sorted(FAKE))
def test_problem_from_fake_server(kind: str) -> None:
    cls, status, title, detail, pointer = FAKE[kind]
    body = {"request_id": "0123456789abcdef", "type": "/problems/" + kind,
            "title": title, "status": status, "detail": detail}
    if pointer:
        body["pointer"] = pointer
    data = json.dumps(body).encode()
    routes = {("POST", "/continue"): lambda _: (
        status, {"Content-Type": "application/problem+json"}, data)}
    with FakeServer(routes) as fake:
        with pytest.raises(stickslip.ProblemError) as info:
            stickslip.Client(fake.url).continuation(params=PAPER)
    check_fields(info.value, cls, status, kind,
                 pointer)
    assert info.value.detail == detail and info.value.body == body
