"""Every problem the daemon answers is raised as its class, with the fields
of its body; the classes cover the daemon's whole table of types."""

from __future__ import annotations

import os
import re
from typing import Any, Callable, Dict, Tuple, Type

import pytest

import stickslip
from stickslip.errors import _BY_TYPE, problem
from conftest import PAPER, Daemon

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))))

CASES: Dict[str, Tuple[Type[stickslip.ProblemError], int,
                       Callable[[stickslip.Client], Any], Any]] = {
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
