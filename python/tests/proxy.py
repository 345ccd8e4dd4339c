"""A proxy in the test process that cuts an answer mid-way."""

from __future__ import annotations

import socket
import threading
from typing import Callable, List, Tuple


def listen(serve: Callable[[socket.socket], None]
           ) -> Tuple[socket.socket, str]:
    """A listening socket on a free loopback port and its URL, with
    ``serve(socket)`` run on a thread of its own to accept from it."""
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    sock.listen(8)
    threading.Thread(target=serve, args=(sock,), daemon=True).start()
    return sock, "http://127.0.0.1:%d" % sock.getsockname()[1]


def read_request(conn: socket.socket) -> Tuple[bytes, bytes]:
    """One request read whole from ``conn``: its head, and its body of
    the head's Content-Length."""
    req = b""
    while b"\r\n\r\n" not in req:
        req += conn.recv(65536)
    head, body = req.split(b"\r\n\r\n", 1)
    sized = head.lower().split(b"content-length: ")
    length = int(sized[1].split(b"\r\n")[0]) if len(sized) > 1 else 0
    while len(body) < length:
        body += conn.recv(65536)
    return head, body


class CuttingProxy:
    """Forwards each connection to the daemon; the first answer to a
    request whose head holds ``when`` is cut after ``keep`` lines of its
    body (the connection closed).  ``requests``: the bodies of the
    requests whose head holds ``when``, ``heads`` every request's head."""

    def __init__(self, target: str, keep: int, when: bytes = b"") -> None:
        host, port = target.split("//")[1].split(":")
        self.target = (host, int(port))
        self.keep = keep
        self.when = when
        self.requests: List[bytes] = []
        self.heads: List[bytes] = []
        self._lock = threading.Lock()
        self.sock, self.url = listen(self.serve)

    def serve(self, sock: socket.socket) -> None:
        while True:
            conn, _ = sock.accept()
            threading.Thread(target=self.one, args=(conn,),
                             daemon=True).start()

    def one(self, conn: socket.socket) -> None:
        up = socket.create_connection(self.target)
        head, body = read_request(conn)
        with self._lock:
            self.heads.append(head)
            ours = self.when in head
            cut = ours and not self.requests
            if ours:
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
