"""A small HTTP server in the test process, for answers the daemon cannot
be made to give on demand (a 503 line inside a batch, a job whose status
moves one item a poll, problems no request provokes, a 503's delay, an
answer cut inside its body).  ``routes``: (method, path) -> a function of the
request's JSON body returning a dict (JSON), a list (NDJSON lines) or a
tuple (status, headers, body bytes)."""

from __future__ import annotations

import json
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any, Callable, Dict, List, Tuple

Route = Callable[..., Any]


class FakeServer:
    def __init__(self, routes: Dict[Tuple[str, str], Route]) -> None:
        self.routes = routes
        self.log: List[Tuple[str, str, Dict[str, str]]] = []
        fake = self

        class Handler(BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.1"

            def handle_one(self, method: str) -> None:
                n = int(self.headers.get("Content-Length") or 0)
                body = json.loads(self.rfile.read(n)) if n else None
                fake.log.append((method, self.path, dict(self.headers)))
                route = fake.routes.get((method, self.path.split("?")[0]))
                if route is None:
                    out: Any = (404, {}, b'{"status":404,"type":'
                                b'"/problems/not-found"}')
                else:
                    out = route(body)
                if isinstance(out, tuple):
                    status, headers, data = out
                elif isinstance(out, list):
                    status, headers = 200, {"Content-Type":
                                            "application/x-ndjson"}
                    data = b"".join(json.dumps(x).encode() + b"\n"
                                    for x in out)
                else:
                    status, headers = 200, {"Content-Type":
                                            "application/json"}
                    data = json.dumps(out).encode()
                self.send_response(status)
                for k, v in headers.items():
                    self.send_header(k, v)
                cut = headers.get("X-Cut")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data[:int(cut)] if cut else data)
                if cut:
                    self.close_connection = True

            def do_GET(self) -> None:
                self.handle_one("GET")

            def do_POST(self) -> None:
                self.handle_one("POST")

            def do_DELETE(self) -> None:
                self.handle_one("DELETE")

            def log_message(self, *args: Any) -> None:
                pass

        self.server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = "http://127.0.0.1:%d" % self.server.server_address[1]

    def __enter__(self) -> "FakeServer":
        threading.Thread(target=self.server.serve_forever,
                         daemon=True).start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.server.shutdown()
        self.server.server_close()
