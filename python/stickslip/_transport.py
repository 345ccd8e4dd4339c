"""HTTP for the client: one connection a request, retries, NDJSON lines.

A request is retried when asking again can help and cannot hurt:
- a 503 that carries Retry-After (a full queue, a spent memory budget, a
  drain), after the delay the daemon asks for (at most 30 s), on every
  call: the daemon refused the request before computing anything;
- a network error (refused, reset, timed out, an answer cut short) on an
  idempotent call only, after 0.1, 0.2, 0.4 ... s (at most 2 s); a call
  that is not idempotent (one that creates a job) is retried only when
  the connection was refused, since then nothing was sent.
Both, and the asking again of an answer cut short (Client), share one
bound: ``retries`` attempts after the first, for the whole call.
"""

from __future__ import annotations

import http.client
import json
import time
import urllib.parse
from typing import Any, Callable, Dict, Iterator, Mapping, Optional

from .errors import ProblemError, TransportError, problem, retryable

USER_AGENT = "stickslip-python"


def encode(body: Any) -> bytes:
    """A request body as compact JSON (NaN and infinities are not JSON)."""
    return json.dumps(body, separators=(",", ":"), allow_nan=False).encode()


class Answer:
    """A successful answer whose body is read as it arrives."""

    def __init__(self, conn: http.client.HTTPConnection,
                 resp: http.client.HTTPResponse) -> None:
        self._conn = conn
        self._resp = resp
        # the attempts made before this one (Transport.open's ``first``)
        self.attempt = 0
        self.status = resp.status
        self.headers = resp.headers

    def header(self, name: str) -> Optional[str]:
        return self._resp.getheader(name)

    def read(self) -> bytes:
        try:
            return self._resp.read()
        except (OSError, http.client.HTTPException) as e:
            raise TransportError("the answer was cut: %s" % e) from e
        finally:
            self.close()

    def json(self) -> Any:
        return json.loads(self.read())

    def lines(self) -> Iterator[Dict[str, Any]]:
        """The NDJSON lines as they arrive; TransportError when the stream
        ends inside a line or the connection drops."""
        try:
            while True:
                try:
                    raw = self._resp.readline()
                except (OSError, http.client.HTTPException) as e:
                    raise TransportError("the stream was cut: %s" % e) from e
                if not raw:
                    return
                if not raw.endswith(b"\n"):
                    raise TransportError("the stream was cut inside a line")
                if raw.strip():
                    yield json.loads(raw)
        finally:
            self.close()

    def close(self) -> None:
        self._resp.close()
        self._conn.close()


def retry_after(value: Optional[str]) -> Optional[float]:
    """Retry-After in seconds (its delay-seconds form; a date is taken as
    one second)."""
    if value is None:
        return None
    try:
        return max(0.0, float(value))
    except ValueError:
        return 1.0


class Transport:
    """Requests to one daemon, with the retries described above."""

    def __init__(self, url: str, timeout: float, retries: int,
                 max_delay: float = 30.0,
                 sleep: Callable[[float], None] = time.sleep) -> None:
        parts = urllib.parse.urlsplit(url)
        if parts.scheme not in ("http", "https") or not parts.hostname:
            raise ValueError("not an http(s) URL: %r" % url)
        self.url = url.rstrip("/")
        self._https = parts.scheme == "https"
        self._host = parts.hostname
        self._port = parts.port
        self._prefix = parts.path.rstrip("/")
        self.timeout = timeout
        self.retries = retries
        self.max_delay = max_delay
        self.sleep = sleep

    def _connect(self) -> http.client.HTTPConnection:
        if self._https:
            return http.client.HTTPSConnection(self._host, self._port,
                                               timeout=self.timeout)
        return http.client.HTTPConnection(self._host, self._port,
                                          timeout=self.timeout)

    def open(self, method: str, path: str, body: Optional[bytes] = None,
             headers: Optional[Mapping[str, str]] = None,
             idempotent: bool = True, first: int = 0) -> Answer:
        """Send a request and return its answer once its status is 2xx or
        3xx; a problem answer is raised as its ProblemError.  ``first``:
        the attempts of this call already made (a request asked again
        because its answer was cut short), counted against ``retries``."""
        h = {"User-Agent": USER_AGENT, "Accept-Encoding": "identity"}
        if body is not None:
            h["Content-Type"] = "application/json"
        h.update(headers or {})
        attempt = first
        while True:
            conn = self._connect()
            try:
                try:
                    conn.request(method, self._prefix + path, body, h)
                except (BrokenPipeError, ConnectionResetError):
                    # the daemon may refuse a body from its headers (413) and
                    # close before it is all sent: its answer is still there
                    pass
                resp = conn.getresponse()
            except (OSError, http.client.HTTPException) as e:
                conn.close()
                refused = isinstance(e, ConnectionRefusedError)
                if attempt < self.retries and (idempotent or refused):
                    self.backoff(attempt)
                    attempt += 1
                    continue
                raise TransportError("%s %s%s: %s" % (method, self.url, path,
                                                      e)) from e
            if resp.status < 400:
                ans = Answer(conn, resp)
                ans.attempt = attempt
                return ans
            exc = self._problem(conn, resp)
            if retryable(exc.status) and exc.retry_after is not None \
                    and attempt < self.retries:
                self.sleep(min(exc.retry_after, self.max_delay))
                attempt += 1
                continue
            raise exc

    def backoff(self, attempt: int) -> None:
        """The wait before the retry after a network error."""
        self.sleep(min(0.1 * 2 ** attempt, 2.0))

    @staticmethod
    def _problem(conn: http.client.HTTPConnection,
                 resp: http.client.HTTPResponse) -> ProblemError:
        try:
            data = resp.read()
        except (OSError, http.client.HTTPException):
            data = b""
        finally:
            conn.close()
        try:
            body = json.loads(data)
        except ValueError:
            body = None
        if not isinstance(body, dict):
            # not a problem document (a proxy's page, libmicrohttpd's own)
            body = {"status": resp.status, "title": resp.reason,
                    "detail": data.decode("utf-8", "replace")[:500]}
        return problem(body, resp.status,
                       retry_after(resp.getheader("Retry-After")))
