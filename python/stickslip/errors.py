"""The daemon's problems (RFC 9457) as exceptions, one class per problem type.

Every problem the daemon answers is a ``ProblemError`` carrying the fields of
its body; its class says what went wrong, so that a caller can catch
``InvalidValue`` or every 422 (``Unprocessable``) or every 503
(``Unavailable``).  The classes follow the daemon's one table of problem
types (``API_PROBLEM_MAP`` in api/include/stickslip_api.h); a type the table
does not know yet is raised as the class of its status.
"""

from __future__ import annotations

from typing import Any, Dict, Mapping, Optional, Tuple, Type


class StickslipError(Exception):
    """Anything the client raises on purpose."""


class TransportError(StickslipError):
    """The daemon could not be reached, or an answer was cut, after retries."""


class ProblemError(StickslipError):
    """A problem answer: ``status``, ``type``, ``title``, ``detail``,
    ``pointer`` (the JSON pointer of the offending field, or None),
    ``request_id``, and for a limit ``limit`` and ``limit_value``;
    ``retry_after`` is the Retry-After delay in seconds where one was sent;
    ``body`` is the whole problem as the daemon wrote it."""

    def __init__(self, body: Mapping[str, Any], status: Optional[int] = None,
                 retry_after: Optional[float] = None) -> None:
        self.body: Dict[str, Any] = dict(body)
        got = self.body.get("status")
        self.status: int = int(got) if isinstance(got, (int, float)) \
            else int(status or 0)
        self.type: str = str(self.body.get("type", "about:blank"))
        self.title: str = str(self.body.get("title", ""))
        self.detail: str = str(self.body.get("detail", ""))
        pointer = self.body.get("pointer")
        self.pointer: Optional[str] = pointer if isinstance(pointer, str) \
            else None
        rid = self.body.get("request_id")
        self.request_id: Optional[str] = rid if isinstance(rid, str) else None
        limit = self.body.get("limit")
        self.limit: Optional[str] = limit if isinstance(limit, str) else None
        value = self.body.get("limit_value")
        self.limit_value: Optional[float] = float(value) \
            if isinstance(value, (int, float)) else None
        self.retry_after = retry_after
        where = " at " + self.pointer if self.pointer else ""
        super().__init__("%d %s: %s%s" % (self.status, self.type, self.detail,
                                           where))

    @property
    def kind(self) -> str:
        """The type's last segment: ``invalid-value`` for
        ``/problems/invalid-value``."""
        return self.type.rsplit("/", 1)[-1]


# By status: what a type this client does not know still is.
class BadRequest(ProblemError):
    """400."""


class NotFound(ProblemError):
    """404: no such path."""


class MethodNotAllowed(ProblemError):
    """405: the path takes another method."""


class ContentTooLarge(ProblemError):
    """413: the body is over ``--max-body``."""


class UnsupportedMediaType(ProblemError):
    """415."""


class Unprocessable(ProblemError):
    """422: the request is JSON but not one the endpoint can compute."""


class ClientClosedRequest(ProblemError):
    """499: the client went away."""


class InternalError(ProblemError):
    """500: a bug of the daemon."""


class Unavailable(ProblemError):
    """503: retried by the client (with Retry-After) before it is raised."""


# By type.
class InvalidJSON(BadRequest):
    """400 invalid-json: the body is not JSON."""


class BadFraming(BadRequest):
    """400 bad-request: framing that could smuggle a request."""


class LimitExceeded(ProblemError):
    """A limit named by ``limit`` (``max_body``, ``max_samples``,
    ``max_batch_items``, ...) with its ``limit_value``: a 413 for the body,
    a 422 for the others (both also instances of their status's class)."""


class BodyTooLarge(LimitExceeded, ContentTooLarge):
    """413 limit-exceeded."""


class RequestOverLimit(LimitExceeded, Unprocessable):
    """422 limit-exceeded."""


class InvalidType(Unprocessable):
    """422 invalid-type: a field has the wrong type."""


class InvalidValue(Unprocessable):
    """422 invalid-value: a field is out of its range or inconsistent."""


class MissingField(Unprocessable):
    """422 missing-field."""


class UnknownField(Unprocessable):
    """422 unknown-field (the detail lists the known ones)."""


class NoConvergence(Unprocessable):
    """422 no-convergence."""


class Overloaded(Unavailable):
    """503 overloaded: every compute slot stayed busy."""


class OutOfMemory(Unavailable):
    """503 out-of-memory: the memory budget is spent."""


class ShuttingDown(Unavailable):
    """503 shutting-down: the daemon is draining."""


class StoreUnavailable(Unavailable):
    """503 store-unavailable: the job store cannot take a new job
    (unreachable, full or read-only); synchronous requests are still
    served."""


_BY_TYPE: Dict[Tuple[str, int], Type[ProblemError]] = {
    ("invalid-json", 400): InvalidJSON,
    ("bad-request", 400): BadFraming,
    ("not-found", 404): NotFound,
    ("method-not-allowed", 405): MethodNotAllowed,
    ("limit-exceeded", 413): BodyTooLarge,
    ("unsupported-media-type", 415): UnsupportedMediaType,
    ("invalid-type", 422): InvalidType,
    ("invalid-value", 422): InvalidValue,
    ("missing-field", 422): MissingField,
    ("unknown-field", 422): UnknownField,
    ("no-convergence", 422): NoConvergence,
    ("limit-exceeded", 422): RequestOverLimit,
    ("client-closed-request", 499): ClientClosedRequest,
    ("internal", 500): InternalError,
    ("overloaded", 503): Overloaded,
    ("out-of-memory", 503): OutOfMemory,
    ("shutting-down", 503): ShuttingDown,
    ("store-unavailable", 503): StoreUnavailable,
}

_BY_STATUS: Dict[int, Type[ProblemError]] = {
    400: BadRequest, 404: NotFound, 405: MethodNotAllowed,
    413: ContentTooLarge, 415: UnsupportedMediaType, 422: Unprocessable,
    499: ClientClosedRequest, 500: InternalError, 503: Unavailable,
}


def problem(body: Mapping[str, Any], status: int,
            retry_after: Optional[float] = None) -> ProblemError:
    """The exception for a problem body answered with ``status``."""
    got = body.get("status")
    code = int(got) if isinstance(got, (int, float)) else status
    kind = str(body.get("type", "")).rsplit("/", 1)[-1]
    cls = _BY_TYPE.get((kind, code)) or _BY_STATUS.get(code) or ProblemError
    return cls(body, code, retry_after)


def retryable(status: int) -> bool:
    """Whether an answer of this status may succeed when asked again later
    (the daemon sends 503 with Retry-After for a full queue, a spent memory
    budget and a drain; nothing else changes by asking again)."""
    return status == 503
