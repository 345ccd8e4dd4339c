"""Streams cut mid-way: a proxy in the test process forwards to the live
daemon and cuts the first answer after its first lines; the client asks
again for what is missing and yields every line once.  And lines yielded
as they arrive, before the answer's end."""

from __future__ import annotations

import json
import socket
import threading

import stickslip
from conftest import PAPER, Daemon
from proxy import CuttingProxy, listen, read_request


def test_batch_cut_resumed(daemon: Daemon) -> None:
    proxy = CuttingProxy(daemon.url, keep=3)
    reqs = [{"id": i, "path": "/orbit",
             "body": {"params": dict(PAPER, ur=0.62 + 0.01 * i),
                      "kind": "overshoot"}} for i in range(8)]
    lines = stickslip.Client(proxy.url).batch(reqs)
    got = list(lines)
    assert sorted(x["index"] for x in got) == list(range(8))
    assert [x["id"] for x in got] == [x["index"] for x in got]
    assert lines.done is not None and lines.done["ok"] == 8
    # the second request asked only for the five items whose lines had not
    # come, and each line is the answer to its own item
    assert len(proxy.requests) == 2
    again = json.loads(proxy.requests[1])["requests"]
    assert len(again) == 5
    seen = {x["id"] for x in got[:3]}
    assert {r["id"] for r in again} == set(range(8)) - seen
    whole = daemon.client().batch(reqs).gather()
    assert [x["body"]["orbits"] for x in sorted(got, key=lambda x: x["index"])
            ] == [x["body"]["orbits"] for x in whole]


def test_map_cut_resumed(daemon: Daemon) -> None:
    proxy = CuttingProxy(daemon.url, keep=2)
    body = {"params": PAPER, "fields": ["period"],
            "axes": [{"parameter": "ur", "from": 0.5, "to": 0.8, "n": 5}]}
    lines = stickslip.Client(proxy.url).map(body)
    got = list(lines)
    assert [x["index"] for x in got] == [[i] for i in range(5)]
    assert got == daemon.client().map(body).gather()
    assert lines.done is not None and lines.done["cells"] == 5
    assert len(proxy.requests) == 2


class Trickle:
    """A server in the test process that answers every POST with one
    NDJSON line, then holds the rest of its answer until ``go`` is set
    (at most 10 s): ``held`` says whether it had to wait the 10 s."""

    def __init__(self, first: bytes, rest: bytes) -> None:
        self.go = threading.Event()
        self.held = False
        self.first, self.rest = first, rest
        self.sock, self.url = listen(self.serve)

    def serve(self, sock: socket.socket) -> None:
        conn, _ = sock.accept()
        read_request(conn)

        def chunk(data: bytes) -> bytes:
            return b"%x\r\n%s\r\n" % (len(data), data)
        conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Type: application/x-ndjson"
                     b"\r\nTransfer-Encoding: chunked\r\n\r\n" +
                     chunk(self.first))
        self.held = not self.go.wait(10)
        conn.sendall(chunk(self.rest) + b"0\r\n\r\n")
        conn.close()


def test_lines_yielded_as_they_arrive() -> None:
    """The first line of a map and of a batch is yielded while the rest of
    the answer has not been sent."""
    cell = json.dumps({"index": [0], "at": {"ur": 0.5}, "orbits": [],
                       "complete": True}).encode() + b"\n"
    item = json.dumps({"id": 0, "index": 0, "status": 200,
                       "body": {}}).encode() + b"\n"
    for first, call in (
            (cell, lambda c: c.map(params=PAPER)),
            (item, lambda c: c.batch([{"path": "/health", "body": {}}]))):
        server = Trickle(first, b'{"done":true}\n')
        lines = call(stickslip.Client(server.url, retries=0))
        assert next(lines) == json.loads(first)
        server.go.set()
        assert list(lines) == [] and lines.done == {"done": True}
        assert not server.held
