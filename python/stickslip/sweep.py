"""Sweeps: many requests of one path, cut under the daemon's limits and
run as /batch jobs (or batches when the daemon runs no jobs), each result
written to a journal as it arrives (but an item still refused 503 after
the client's retries: returned, and sent again by the next call).

    results = client.sweep(bodies, path="/orbit", journal="sweep.jsonl")

``items`` are request bodies for ``path``, or ``{"id": ..., "body": ...}``
pairs when the caller names them (an unnamed item's id is its position).
The results come back in the items' order, each ``{"id", "status",
"body"}`` as a /batch line gives it: a problem is a result too (its status
says so), and "no orbit" is a 200 whose body has a ``reason``.

Each cut is posted to /batch with ``Prefer: respond-async``.  A daemon with
jobs answers 201 and the cut is a job: it takes up to ``--max-job-items``
items (1000000) and a body of ``--max-job-body`` (256 MiB), and its results
are read as they are stored.  A daemon without jobs (--no-jobs) ignores the
preference and answers the batch itself: from then on cuts hold at most
``--max-batch-items`` (10000) items and ``--max-body`` (1 MiB), and so does
the first cut, before the daemon has said which it is.  A job store that
cannot take a job (503 store-unavailable) turns the sweep to batches too.
When the daemon names a lower limit in a 413 or a 422 ``limit-exceeded``,
the cut is made again under the limit it names.  An item answered 503 (the
daemon's queue full, its memory spent, a drain) is sent again in a later
cut after a second, the daemon's Retry-After, up to the client's retries.

The journal (JSON lines: a header naming the path, then one result a line,
with a hash of the request, and a line for each job naming its items) is
appended to and flushed as each result arrives (503s aside); a second
call with the same journal sends only the items whose results it lacks, or
whose body has changed, and ignores a last line torn by an interruption.
A job goes on at the daemon when its sweep is interrupted: the second call
reads the results of the journal's jobs (those still running as they
come), and sends again only the items of a job the daemon no longer has
(dismissed, or expired after ``--job-ttl``).
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from typing import (IO, TYPE_CHECKING, Any, Dict, Iterable, List, Optional,
                    Sequence, Tuple)

from ._transport import encode
from .errors import LimitExceeded, NotFound, StoreUnavailable
from .jobs import ASYNC, Job, job_of
from .progress import Progress

if TYPE_CHECKING:
    from .client import Client, Lines

JSON = Dict[str, Any]
MAX_ITEMS = 10000
MAX_BODY = 1 << 20
MAX_JOB_ITEMS = 1000000
MAX_JOB_BODY = 256 << 20
RETRY_DELAY = 1.0
HEADER = "stickslip_sweep"
JOB = "stickslip_job"


class Item:
    __slots__ = ("id", "body", "key", "text", "digest")

    def __init__(self, ident: Any, body: Any, path: str) -> None:
        self.id = ident
        self.body = body
        self.key = json.dumps(ident, sort_keys=True)
        # the item as it is sent inside a batch, and the hash that ties a
        # journaled result to the request it answers
        self.text = encode({"path": path, "body": body})
        self.digest = hashlib.sha256(
            json.dumps(body, sort_keys=True).encode()).hexdigest()[:16]


def _items(items: Iterable[Any], path: str) -> List[Item]:
    out: List[Item] = []
    seen = set()
    for i, x in enumerate(items):
        named = isinstance(x, dict) and set(x) == {"id", "body"}
        item = Item(x["id"], x["body"], path) if named else Item(i, x, path)
        if item.key in seen:
            raise ValueError("two items have the id %s" % item.key)
        seen.add(item.key)
        out.append(item)
    return out


def _read_journal(name: str, path: str
                  ) -> Tuple[Dict[str, JSON], List[JSON], int]:
    """The journaled results by key, its job lines, and the length of the
    file's whole lines (a torn last line is cut off before appending)."""
    done: Dict[str, JSON] = {}
    jobs: List[JSON] = []
    good = 0
    with open(name, "rb") as f:
        for raw in f:
            if not raw.endswith(b"\n"):
                break
            try:
                line = json.loads(raw)
            except ValueError:
                break
            if HEADER in line:
                if line.get("path") != path:
                    raise ValueError("the journal %s is a sweep of %s, not %s"
                                     % (name, line.get("path"), path))
            elif JOB in line:
                jobs.append(line)
            else:
                done[json.dumps(line["id"], sort_keys=True)] = line
            good += len(raw)
    return done, jobs, good


def _open_journal(name: Optional[str], path: str
                  ) -> Tuple[Dict[str, JSON], List[JSON], Optional[IO[str]]]:
    if name is None:
        return {}, [], None
    done: Dict[str, JSON] = {}
    jobs: List[JSON] = []
    if os.path.exists(name):
        done, jobs, good = _read_journal(name, path)
        with open(name, "r+b") as f:
            f.truncate(good)
    f2 = open(name, "a", encoding="utf-8")
    if f2.tell() == 0:
        f2.write(json.dumps({HEADER: 1, "path": path}) + "\n")
        f2.flush()
    return done, jobs, f2


def _cut(queue: List[Item], max_items: int, max_body: int) -> int:
    """How many items of the queue's head fit in one batch."""
    size = len(b'{"requests":[]}')
    n = 0
    for item in queue[:max_items]:
        size += len(item.text) + 1
        if n and size > max_body:
            break
        n += 1
    return n


def sweep(client: "Client", items: Iterable[Any], path: str = "/orbit",
          journal: Optional[str] = None, progress: bool = False,
          max_items: Optional[int] = None) -> List[JSON]:
    todo = _items(items, path)
    done, jobs, out = _open_journal(journal, path)
    results: Dict[str, JSON] = {
        it.key: done[it.key] for it in todo
        if it.key in done and done[it.key].get("request") == it.digest}
    bar = Progress(len(todo), "sweep " + path, len(results), progress)
    run = _Run(client, results, out, bar, max_items)
    try:
        by_key = {it.key: it for it in todo}
        for line in jobs:
            run.attach(line, by_key)
        queue = [it for it in todo if it.key not in results]
        while queue:
            n = _cut(queue, run.limits["max_batch_items"], run.body_limit())
            chunk, queue = queue[:n], queue[n:]
            try:
                again = run.send(chunk)
            except LimitExceeded as e:
                run.lower(e, n)
                queue = chunk + queue
                continue
            except StoreUnavailable:
                if run.jobs is False:
                    raise
                run.use_jobs(False)  # batches are still served
                queue = chunk + queue
                continue
            if again:
                time.sleep(RETRY_DELAY)
                queue = again + queue
    finally:
        bar.close()
        if out is not None:
            out.close()
    return [_public(results[it.key]) for it in todo]


class _Run:
    """A sweep's results, journal and progress, and what it knows of the
    daemon: ``jobs`` (None until its first answer says) and the limits
    its cuts are made under."""

    def __init__(self, client: "Client", results: Dict[str, JSON],
                 out: Optional[IO[str]], bar: Progress,
                 max_items: Optional[int]) -> None:
        self.client = client
        self.results = results
        self.out = out
        self.bar = bar
        self.max_items = max_items
        self.tries: Dict[str, int] = {}
        self.jobs: Optional[bool] = None
        self.limits: Dict[str, int] = {}
        self.use_jobs(None)

    def use_jobs(self, jobs: Optional[bool]) -> None:
        """Take the limits of jobs (True) or of batches (False, and None:
        the first cut must also suit a daemon without jobs)."""
        if jobs == self.jobs and self.limits:
            return
        self.jobs = jobs
        self.limits = {"max_batch_items": MAX_JOB_ITEMS,
                       "max_job_body": MAX_JOB_BODY} if jobs else \
            {"max_batch_items": MAX_ITEMS, "max_body": MAX_BODY}
        if self.max_items:
            self.limits["max_batch_items"] = min(
                self.max_items, self.limits["max_batch_items"])

    def body_limit(self) -> int:
        return self.limits.get("max_job_body") or self.limits["max_body"]

    def lower(self, e: LimitExceeded, n: int) -> None:
        """Take in a limit the daemon named (only a daemon with jobs names
        max_job_body); one item over it is the caller's."""
        if e.limit == "max_job_body":
            self.use_jobs(True)
        name = e.limit or ""
        if name not in self.limits or e.limit_value is None or n <= 1:
            raise e
        self.limits[name] = min(int(e.limit_value), self.limits[name] - 1)

    def send(self, chunk: List[Item]) -> List[Item]:
        """One cut as a job, or as a batch when the daemon answers it
        itself; the items to send again (answered 503, tries left)."""
        def encoded(left: List[int]) -> bytes:
            return b'{"requests":[' + \
                b",".join(chunk[i].text for i in left) + b"]}"

        if self.jobs is False:
            return self.take(chunk, self.client.batch_encoded(len(chunk),
                                                              encoded))
        ans = self.client.open("POST", "/batch", encoded(list(range(len(
            chunk)))), ASYNC, idempotent=False)
        if ans.status != 201:
            self.use_jobs(False)
            return self.take(chunk, self.client.batch_encoded(
                len(chunk), encoded, ans))
        self.use_jobs(True)
        job = job_of(self.client, ans)
        self.journal({JOB: job.id, "ids": [it.id for it in chunk],
                      "requests": [it.digest for it in chunk]})
        return self.take(chunk, job.results())

    def attach(self, line: JSON, by_key: Dict[str, Item]) -> None:
        """The results of a journaled job for the items still wanted (of
        the same body); nothing when the daemon no longer has the job."""
        chunk: List[Optional[Item]] = []
        for ident, digest in zip(line.get("ids") or [],
                                 line.get("requests") or []):
            it = by_key.get(json.dumps(ident, sort_keys=True))
            wanted = it is not None and it.key not in self.results and \
                it.digest == digest
            chunk.append(it if wanted else None)
        if not any(chunk):
            return
        job = Job(self.client, "/jobs/%s" % line[JOB], {})
        try:
            self.take(chunk, job.results())
        except NotFound:
            pass  # dismissed or expired: its items are sent again

    def take(self, chunk: Sequence[Optional[Item]],
             lines: "Lines") -> List[Item]:
        """The lines of a cut as results, journaled; the items answered
        503 with tries left, to send again."""
        again: List[Item] = []
        for line in lines:
            it = chunk[line["index"]]
            if it is None:
                continue
            result = {"id": it.id, "status": line["status"],
                      "body": line["body"], "request": it.digest}
            if line["status"] == 503:
                self.tries[it.key] = self.tries.get(it.key, 0) + 1
                if self.tries[it.key] <= self.client.retries:
                    again.append(it)
                    continue
                self.results[it.key] = result  # returned, not journaled
                self.bar.update()
                continue
            self.results[it.key] = result
            self.journal(result)
            self.bar.update()
        return again

    def journal(self, line: JSON) -> None:
        if self.out is not None:
            self.out.write(json.dumps(line, separators=(",", ":")) + "\n")
            self.out.flush()


def _public(result: JSON) -> JSON:
    return {k: result[k] for k in ("id", "status", "body")}
