"""Jobs: a computing request run by the daemon on its own time (OGC API -
Processes, Part 1).

``client.submit(path, body)`` posts the request with ``Prefer:
respond-async``; the daemon answers 201 with ``Location: /jobs/{id}`` and
the job's status document.  ``Job.status()`` reads ``GET /jobs/{id}``
(``status``: accepted, running, successful, failed, dismissed;
``progress`` 0-100; ``items``: ``{"done", "total"}`` where the job counts
items), ``wait()`` polls it with a progress bar, ``results()`` reads
``GET /jobs/{id}/results`` (the synchronous answer, streamed while it grows
for the NDJSON endpoints) and ``cancel()`` sends ``DELETE /jobs/{id}``.

A daemon that runs no jobs answers the request itself (200): the Job is
then already successful and holds that answer.
"""

from __future__ import annotations

import json
import time
from typing import TYPE_CHECKING, Any, Dict, Iterator, Optional

from ._transport import Answer, encode
from .errors import StickslipError, TransportError
from .progress import Progress

if TYPE_CHECKING:
    from .client import Client, Lines

JSON = Dict[str, Any]
FINAL = ("successful", "failed", "dismissed")
ASYNC = {"Prefer": "respond-async"}


class JobFailed(StickslipError):
    """The job ended failed or dismissed; ``status`` is its last status
    document."""

    def __init__(self, status: JSON) -> None:
        self.status = status
        super().__init__("job %s %s" % (status.get("jobID", "?"),
                                        status.get("status")))


class Job:
    def __init__(self, client: "Client", location: Optional[str],
                 status: JSON, answer: Optional[bytes] = None,
                 ndjson: bool = False) -> None:
        self._client = client
        self.location = location
        self.last: JSON = status
        self._answer = answer
        self._ndjson = ndjson

    @property
    def id(self) -> Optional[str]:
        """The job's id (the last segment of its Location)."""
        if self.location is None:
            return None
        return self.location.rstrip("/").rsplit("/", 1)[-1]

    @property
    def progress(self) -> int:
        """The progress 0-100 of the last status read."""
        return int(self.last.get("progress", 0))

    def status(self) -> JSON:
        """GET /jobs/{id}: the status document, kept in ``last``."""
        if self.location is not None:
            self.last = self._client.request("GET", self.location)
        return self.last

    def wait(self, progress: bool = True, poll: float = 0.5,
             timeout: Optional[float] = None) -> JSON:
        """Poll the status until the job ends; its last status document.
        ``progress``: a bar of its items (or of percent) while it runs.
        Raises JobFailed when it failed or was dismissed, TimeoutError
        after ``timeout`` seconds."""
        start = time.monotonic()
        st = self.last
        items = st.get("items") if isinstance(st.get("items"), dict) else None
        total = int(items["total"]) if items else 100
        bar = Progress(total, "job " + (self.id or ""), 0, progress)
        try:
            while True:
                items = st.get("items")
                bar.set(int(items["done"]) if isinstance(items, dict)
                        else int(st.get("progress", 0)))
                if st.get("status") in FINAL:
                    break
                if timeout is not None and \
                        time.monotonic() - start > timeout:
                    raise TimeoutError("job %s still %s" % (self.id,
                                                            st.get("status")))
                time.sleep(poll)
                st = self.status()
        finally:
            bar.close()
        if st.get("status") != "successful":
            raise JobFailed(st)
        return st

    def results(self) -> "Lines":
        """GET /jobs/{id}/results as lines: an NDJSON answer's lines as they
        are stored (resumed after the lines already read when the stream
        drops), or the one document of a single answer."""
        from .client import Lines
        if self._answer is not None:
            return Lines(self._stored(), lambda line: line.get("index", 0))
        return Lines(self._stream(), lambda line: line.get("index", 0))

    def _stored(self) -> Iterator[JSON]:
        text = (self._answer or b"").decode()
        if not self._ndjson:
            yield json.loads(text)
            return
        for raw in text.splitlines():
            if raw.strip():
                yield json.loads(raw)

    def _stream(self) -> Iterator[JSON]:
        read = 0  # the answer is the same bytes each time: skip what was read
        path = "%s/results" % self.location
        failures = 0  # cuts in a row with no new line between them
        while True:
            ans: Answer = self._client.open("GET", path)
            ctype = ans.header("Content-Type") or ""
            if "ndjson" not in ctype:
                yield ans.json()
                return
            before = read
            try:
                for i, line in enumerate(ans.lines()):
                    if i >= read:
                        read += 1
                        yield line
                    if line.get("done") is True:
                        return
                raise TransportError("the results ended before their last "
                                     "line")
            except TransportError:
                failures = 0 if read > before else failures + 1
                if failures > self._client.retries:
                    raise

    def cancel(self) -> JSON:
        """DELETE /jobs/{id}: its work stops and its results are deleted;
        its status document (dismissed), kept in ``last``."""
        if self.location is not None:
            self.last = self._client.request("DELETE", self.location)
        return self.last


def job_of(client: "Client", ans: Answer) -> Job:
    """The Job of a 201 answer to a request with Prefer: respond-async."""
    location = ans.header("Location")
    if location is None:
        raise StickslipError("201 without a Location")
    if "://" in location:
        location = "/" + location.split("://", 1)[1].split("/", 1)[1]
    status: JSON = ans.json()
    return Job(client, location, status)


def submit(client: "Client", path: str, body: JSON) -> Job:
    ans = client.open("POST", path, encode(body), ASYNC, idempotent=False)
    if ans.status == 201:
        return job_of(client, ans)
    ndjson = "ndjson" in (ans.header("Content-Type") or "")
    return Job(client, None, {"status": "successful", "progress": 100},
               ans.read(), ndjson)
