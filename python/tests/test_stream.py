"""Streams cut mid-way: a proxy in the test process forwards to the live
daemon and cuts the first answer after its first lines; the client asks
again for what is missing and yields every line once."""

from __future__ import annotations

import json
import socket
import threading
from typing import List

import stickslip
from conftest import PAPER, Daemon


class CuttingProxy:
    """Forwards each connection to the daemon; the first answer is cut
    after ``keep`` lines of its body (the connection closed)."""

    def __init__(self, target: str, keep: int) -> None:
        host, port = target.split("//")[1].split(":")
        self.target = (host, int(port))
        self.keep = keep
        self.requests: List[bytes] = []
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.url = "http://127.0.0.1:%d" % self.sock.getsockname()[1]
        threading.Thread(target=self.serve, daemon=True).start()

    def serve(self) -> None:
        while True:
            conn, _ = self.sock.accept()
            cut = not self.requests
            threading.Thread(target=self.one, args=(conn, cut),
                             daemon=True).start()

    def one(self, conn: socket.socket, cut: bool) -> None:
        up = socket.create_connection(self.target)
        req = b""
        while b"\r\n\r\n" not in req:
            req += conn.recv(65536)
        head, body = req.split(b"\r\n\r\n", 1)
        length = int(head.lower().split(b"content-length: ")[1]
                     .split(b"\r\n")[0])
        while len(body) < length:
            body += conn.recv(65536)
        self.requests.append(body)
        up.sendall(head + b"\r\n\r\n" + body)
        got = b""
        while True:
            data = up.recv(65536)
            if not data:
                break
            got += data
            if cut and got.count(b"}\n") >= self.keep:
                # keep the first lines whole and half of the next one
                end = 0
                for _ in range(self.keep):
                    end = got.index(b"}\n", end) + 2
                conn.sendall(got[:end + 10])
                break
            if not cut:
                conn.sendall(data)
                got = b""
        conn.close()
        up.close()


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
