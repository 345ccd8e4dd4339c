"""Sweeps: many requests of one path, cut into batches under the daemon's
limits, each result written to a journal as it arrives.

    results = client.sweep(bodies, path="/orbit", journal="sweep.jsonl")

``items`` are request bodies for ``path``, or ``{"id": ..., "body": ...}``
pairs when the caller names them (an unnamed item's id is its position).
The results come back in the items' order, each ``{"id", "status",
"body"}`` as a /batch line gives it: a problem is a result too (its status
says so), and "no orbit" is a 200 whose body has a ``reason``.

Batches hold at most ``max_items`` items (the daemon's ``--max-batch-items``
default, 10000) and a body of at most ``--max-body`` (1 MiB): when the
daemon names a lower limit in a 413 or a 422 ``limit-exceeded``, the batch is
cut again under the limit it names.  An item answered 503 (the daemon's
queue full, its memory spent, a drain) is sent again in a later batch after
a second, the daemon's Retry-After, up to the client's retries.

The journal (JSON lines: a header naming the path, then one result a line,
with a hash of the request) is appended to and flushed as each result
arrives; a second call with the same journal sends only the items whose
results it lacks, or whose body has changed, and ignores a last line torn
by an interruption.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from typing import (IO, TYPE_CHECKING, Any, Dict, Iterable, List, Optional,
                    Tuple)

from ._transport import encode
from .errors import LimitExceeded
from .progress import Progress

if TYPE_CHECKING:
    from .client import Client

JSON = Dict[str, Any]
MAX_ITEMS = 10000
MAX_BODY = 1 << 20
RETRY_DELAY = 1.0
HEADER = "stickslip_sweep"


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


def _read_journal(name: str, path: str) -> Tuple[Dict[str, JSON], int]:
    """The journaled results by key, and the length of the file's whole
    lines (a torn last line is cut off before appending)."""
    done: Dict[str, JSON] = {}
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
            else:
                done[json.dumps(line["id"], sort_keys=True)] = line
            good += len(raw)
    return done, good


def _open_journal(name: Optional[str], path: str
                  ) -> Tuple[Dict[str, JSON], Optional[IO[str]]]:
    if name is None:
        return {}, None
    done: Dict[str, JSON] = {}
    if os.path.exists(name):
        done, good = _read_journal(name, path)
        with open(name, "r+b") as f:
            f.truncate(good)
    f2 = open(name, "a", encoding="utf-8")
    if f2.tell() == 0:
        f2.write(json.dumps({HEADER: 1, "path": path}) + "\n")
        f2.flush()
    return done, f2


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
    done, out = _open_journal(journal, path)
    results: Dict[str, JSON] = {
        it.key: done[it.key] for it in todo
        if it.key in done and done[it.key].get("request") == it.digest}
    queue = [it for it in todo if it.key not in results]
    limits = {"max_batch_items": max_items or MAX_ITEMS,
              "max_body": MAX_BODY}
    tries: Dict[str, int] = {}
    bar = Progress(len(todo), "sweep " + path, len(results), progress)
    try:
        while queue:
            n = _cut(queue, limits["max_batch_items"], limits["max_body"])
            chunk, queue = queue[:n], queue[n:]
            try:
                again = _batch(client, chunk, results, out, bar, tries)
            except LimitExceeded as e:
                _lower(limits, e, n)
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


def _lower(limits: Dict[str, int], e: LimitExceeded, n: int) -> None:
    """Take in a limit the daemon named; one item over it is the caller's."""
    name = e.limit or ""
    if name not in limits or e.limit_value is None or n <= 1:
        raise e
    limits[name] = min(int(e.limit_value), limits[name] - 1)


def _batch(client: "Client", chunk: List[Item], results: Dict[str, JSON],
           out: Optional[IO[str]], bar: Progress,
           tries: Dict[str, int]) -> List[Item]:
    """One batch; the items to send again (answered 503, tries left)."""
    def encoded(left: List[int]) -> bytes:
        return b'{"requests":[' + b",".join(chunk[i].text for i in left) + \
            b"]}"

    again: List[Item] = []
    for line in client.batch_encoded(len(chunk), encoded):
        it = chunk[line["index"]]
        result = {"id": it.id, "status": line["status"],
                  "body": line["body"], "request": it.digest}
        if line["status"] == 503:
            tries[it.key] = tries.get(it.key, 0) + 1
            if tries[it.key] <= client.retries:
                again.append(it)
                continue
            results[it.key] = result  # returned, not journaled
            bar.update()
            continue
        results[it.key] = result
        if out is not None:
            out.write(json.dumps(result, separators=(",", ":")) + "\n")
            out.flush()
        bar.update()
    return again


def _public(result: JSON) -> JSON:
    return {k: result[k] for k in ("id", "status", "body")}
