"""The client: one method per computing endpoint of stickslipd, and for
/health, /version and /metrics; jobs through ``submit`` (a ``Job``), any
other resource (GET /jobs, a problem's page) through ``open`` and
``request``.

Each computing method takes the request's fields as keyword arguments, with
the names of the JSON contract (api/openapi.json), or one dict, or both (the
keywords win), and returns the answer as the contract gives it: dicts and
lists.  ``map`` and ``batch`` answer NDJSON and return ``Lines``, which
yields the lines as they arrive.
"""

from __future__ import annotations

from typing import (TYPE_CHECKING, Any, Callable, Dict, Iterable, Iterator,
                    List, Mapping, Optional, Sequence, Set, Tuple, Union)

from ._transport import Answer, Transport, encode
from .errors import TransportError

if TYPE_CHECKING:
    from .jobs import Job

Body = Mapping[str, Any]
JSON = Dict[str, Any]


def _body(body: Optional[Body], fields: Mapping[str, Any]) -> JSON:
    merged: JSON = dict(body or {})
    merged.update(fields)
    return merged


class Lines(Iterator[JSON]):
    """The lines of an NDJSON answer, yielded as they arrive; the last line
    (``{"done": true, ...}``) is not yielded but kept in ``done`` once the
    stream has ended.  A stream cut before its last line is asked again (up
    to the client's retries) and goes on where it was: the lines already
    yielded are not yielded twice."""

    def __init__(self, lines: Iterator[JSON], order: Callable[[JSON], Any]):
        self._lines = lines
        self._order = order
        self.done: Optional[JSON] = None

    def __iter__(self) -> "Lines":
        return self

    def __next__(self) -> JSON:
        line = next(self._lines)
        while line.get("done") is True:
            self.done = line
            line = next(self._lines)
        return line

    def gather(self) -> List[JSON]:
        """Every line (but the last) in the order of the request: a map's
        cells in row-major order, a batch's items by index."""
        return sorted(self, key=self._order)


class Client:
    """A client of one stickslipd.

    ``timeout``: seconds to wait for the connection and for each read (a
    computation answers when it is done: allow for ``--max-seconds``);
    ``retries``: attempts after the first, for the whole of a call: for a
    503 with Retry-After, for network errors on idempotent calls (every
    call but ``submit`` and the ``/batch`` cuts of ``sweep``: the computing
    endpoints have no effect but their answer), and for an answer cut
    short."""

    def __init__(self, url: str = "http://127.0.0.1:8080",
                 timeout: float = 60.0, retries: int = 3) -> None:
        self._t = Transport(url, timeout, retries)

    @property
    def url(self) -> str:
        return self._t.url

    @property
    def retries(self) -> int:
        return self._t.retries

    # ---- plain requests --------------------------------------------------

    def open(self, method: str, path: str, body: Union[bytes, Any] = None,
             headers: Optional[Mapping[str, str]] = None,
             idempotent: bool = True) -> Answer:
        """Any request; ``body`` as bytes is sent as it is, anything else as
        JSON.  Problems are raised, 503 and network errors retried."""
        data = body if isinstance(body, bytes) or body is None \
            else encode(body)
        return self._t.open(method, path, data, headers, idempotent)

    def request(self, method: str, path: str, body: Union[bytes, Any] = None,
                headers: Optional[Mapping[str, str]] = None) -> Any:
        """Any idempotent request whose answer is one JSON document; an
        answer cut short is asked again, as a network error is."""
        data = body if isinstance(body, bytes) or body is None \
            else encode(body)
        attempt = 0
        while True:
            ans = self._t.open(method, path, data, headers, first=attempt)
            attempt = ans.attempt
            try:
                return ans.json()
            except TransportError:
                if attempt >= self._t.retries:
                    raise
                self._t.backoff(attempt)
                attempt += 1

    def _post(self, path: str, body: Optional[Body],
              fields: Mapping[str, Any]) -> JSON:
        answer: JSON = self.request("POST", path, _body(body, fields))
        return answer

    # ---- the endpoints ---------------------------------------------------

    def orbit(self, body: Optional[Body] = None, /, **fields: Any) -> JSON:
        """POST /orbit: the periodic orbits of a parameter set."""
        return self._post("/orbit", body, fields)

    def simulate(self, body: Optional[Body] = None, /, **fields: Any) -> JSON:
        """POST /simulate: a motion from a state, exactly, event by event."""
        return self._post("/simulate", body, fields)

    def stability(self, body: Optional[Body] = None, /,
                  **fields: Any) -> JSON:
        """POST /stability: the Poincare map's Jacobian of an orbit."""
        return self._post("/stability", body, fields)

    def continuation(self, body: Optional[Body] = None, /,
                     **fields: Any) -> JSON:
        """POST /continue: a family of orbits in one parameter."""
        return self._post("/continue", body, fields)

    def basins(self, body: Optional[Body] = None, /, **fields: Any) -> JSON:
        """POST /basins: the attractors and their basins over a slice."""
        return self._post("/basins", body, fields)

    def health(self) -> JSON:
        """GET /health."""
        answer: JSON = self.request("GET", "/health")
        return answer

    def version(self) -> JSON:
        """GET /version."""
        answer: JSON = self.request("GET", "/version")
        return answer

    def metrics(self) -> str:
        """GET /metrics, the Prometheus text."""
        return self.open("GET", "/metrics").read().decode()

    def map(self, body: Optional[Body] = None, /, **fields: Any) -> Lines:
        """POST /map: one line per cell (``index``, ``at``, ``orbits``,
        ``complete``).  The daemon writes the cells when the whole map is
        done, so a map cut mid-way is asked again whole and the cells
        already yielded are skipped."""
        data = encode(_body(body, fields))
        first = self._t.open("POST", "/map", data)
        seen: Set[Tuple[int, ...]] = set()

        def lines() -> Iterator[JSON]:
            ans: Optional[Answer] = first
            attempt = first.attempt
            while True:
                if ans is None:
                    ans = self._t.open("POST", "/map", data, first=attempt)
                    attempt = ans.attempt
                try:
                    for line in ans.lines():
                        if line.get("done") is True:
                            yield line
                            return
                        key = tuple(line["index"])
                        if key not in seen:
                            seen.add(key)
                            yield line
                    raise TransportError("the map ended before its last line")
                except TransportError:
                    if attempt >= self._t.retries:
                        raise
                attempt += 1
                ans = None

        return Lines(lines(), lambda line: tuple(line["index"]))

    def batch(self, body: Union[Body, Sequence[Body], None] = None, /,
              **fields: Any) -> Lines:
        """POST /batch: one line per item (``id``, ``index``, ``status``,
        ``body``) in the order the items finish.  ``body`` may be the list
        of requests itself.  A batch cut mid-way is asked again for the
        items whose lines had not come, and their lines keep their index in
        the request."""
        req = _body({"requests": body} if isinstance(body, (list, tuple))
                    else body, fields)  # type: ignore[arg-type]
        items: List[Any] = list(req.get("requests") or [])
        return self.batch_encoded(
            len(items),
            lambda left: encode(dict(req, requests=[items[i] for i in left])))

    def batch_encoded(self, n: int,
                      encoded: Callable[[List[int]], bytes],
                      first: Optional[Answer] = None) -> Lines:
        """POST /batch of ``n`` items whose body ``encoded(indexes)`` writes
        for those of the items given (all of them first, then those a cut
        stream left without a line).  ``first``: the answer to the first
        POST when it was already sent."""
        left = list(range(n))
        if first is None:
            first = self._t.open("POST", "/batch", encoded(left))
        return Lines(self._batch_lines(encoded, left, first),
                     lambda line: line["index"])

    def _batch_lines(self, encoded: Callable[[List[int]], bytes],
                     left: List[int], ans: Optional[Answer]) -> Iterator[JSON]:
        seconds = 0.0
        counts = {"ok": 0, "failed": 0}
        attempt = ans.attempt if ans is not None else 0
        asked_again = False
        while True:
            if ans is None:
                ans = self._t.open("POST", "/batch", encoded(left),
                                   first=attempt)
                attempt = ans.attempt
            got: Set[int] = set()
            try:
                for line in ans.lines():
                    if line.get("done") is True:
                        seconds += float(line.get("seconds", 0.0))
                        if not asked_again:
                            yield line
                        else:
                            yield dict(line, seconds=seconds, **counts)
                        return
                    line["index"] = left[line["index"]]
                    got.add(line["index"])
                    counts["ok" if line["status"] == 200 else "failed"] += 1
                    yield line
                raise TransportError("the batch ended before its last line")
            except TransportError:
                if attempt >= self._t.retries:
                    raise
            attempt += 1
            asked_again = True
            left = [i for i in left if i not in got]
            ans = None

    # ---- sweeps and jobs -------------------------------------------------

    def sweep(self, items: Iterable[Any], path: str = "/orbit",
              journal: Optional[str] = None, progress: bool = False,
              max_items: Optional[int] = None) -> List[JSON]:
        """Many requests of one path, as /batch jobs (or batches when the
        daemon runs no jobs); see stickslip.sweep."""
        from .sweep import sweep
        return sweep(self, items, path, journal, progress, max_items)

    def submit(self, path: str, body: Optional[Body] = None, /,
               **fields: Any) -> "Job":
        """A computing request as a job (``Prefer: respond-async``)."""
        from .jobs import submit
        return submit(self, path, _body(body, fields))

