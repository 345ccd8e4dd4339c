#!/usr/bin/env python3
"""The daemon's answers to framing that libmicrohttpd reads loosely, its
access logs, the client it sees behind a trusted proxy, and its new metrics,
over raw sockets.

    check_framing.py STICKSLIPD [CHECK...]

Each check starts its own daemon on port 0 and reads its URL from stderr;
with no CHECK every check runs.  Exit 0 when all pass, 1 otherwise.
"""
import json
import re
import socket
import subprocess
import sys
import threading
import time
import urllib.request

PAPER = '"params":{"chi":0.2,"eta":4,"us":0.0724,"ur":0.6178,"V":1}'
X0 = "[1.2739277342427062,4.3629277342427093,-0.80748713672430694,1.0]"
# minutes of work (ends when cancelled), and microseconds of it
LONG_SIM = '{%s,"initial":%s,"t_end":9e8,"events":false}' % (PAPER, X0)
LONG_FLAGS = ("--max-horizon", "1e10", "--max-events", "1000000000",
              "--max-seconds", "600")
SHORT_SIM = '{%s,"initial":%s,"t_end":2}' % (PAPER, X0)
POST = ("POST /simulate HTTP/1.1\r\nHost: x\r\n"
        "Content-Type: application/json\r\n")


class Daemon:
    """stickslipd on port 0; its stderr lines collected as they come."""

    def __init__(self, binary, *flags):
        self.p = subprocess.Popen([binary, "--port", "0", *flags],
                                  stderr=subprocess.PIPE, text=True,
                                  errors="replace")
        m = re.search(r"http://([^ \n]+):(\d+)", self.p.stderr.readline())
        if not m:
            self.p.kill()
            sys.exit("check_framing: the daemon did not start")
        self.port = int(m.group(2))
        self.url = "http://127.0.0.1:%d" % self.port
        self.lines = []
        self.t = threading.Thread(target=self._read, daemon=True)
        self.t.start()

    def _read(self):
        for line in self.p.stderr:
            self.lines.append(line)

    def log(self, want, seconds=5):
        """The JSON access lines, once one satisfies @want (or the time is
        up)."""
        end = time.time() + seconds
        while True:
            got = []
            for line in list(self.lines):
                try:
                    got.append(json.loads(line))
                except ValueError:
                    pass
            if any(want(g) for g in got) or time.time() > end:
                return got
            time.sleep(0.05)

    def stop(self):
        self.p.terminate()
        try:
            self.p.wait(20)
        except subprocess.TimeoutExpired:
            self.p.kill()
        self.t.join(5)


def exchange(port, data, seconds=3.0, keep_sending=None):
    """Send @data on a new connection and read until the daemon closes it or
    @seconds pass: (bytes read, closed by the daemon, seconds taken)."""
    s = socket.create_connection(("127.0.0.1", port))
    s.settimeout(seconds)
    t0 = time.time()
    out, closed = b"", False
    try:
        s.sendall(data)
        if keep_sending:
            keep_sending(s)
        while True:
            k = s.recv(65536)
            if not k:
                closed = True
                break
            out += k
    except (socket.timeout, ConnectionResetError, BrokenPipeError):
        pass
    finally:
        s.close()
    return out, closed, time.time() - t0


def status_of(raw):
    m = re.match(rb"HTTP/1\.1 (\d{3}) ", raw)
    return int(m.group(1)) if m else None


def refused(d, data, want, why):
    """@data is answered @want at once, once, and the connection closed."""
    raw, closed, dt = exchange(d.port, data)
    st = status_of(raw)
    heads = len(re.findall(rb"(?:^|\r\n)HTTP/1\.1 \d{3} ", raw))
    ok = st == want and closed and dt < 2 and heads == 1
    if not ok:
        print("  %s: status %s, closed %s, %.2f s, %d status lines: %r" %
              (why, st, closed, dt, heads, raw[:300]))
    return ok


# ---- framing ---------------------------------------------------------------

def check_space_before_colon(binary):
    """`Content-Length : N` and `Transfer-Encoding : chunked` are not taken
    as other headers (the request hidden in the body is not answered)."""
    d = Daemon(binary, "--quiet")
    hidden = b"GET /health HTTP/1.1\r\nHost: x\r\n\r\n"
    body = b"{}" + hidden
    try:
        a = refused(d, POST.encode() + b"Content-Length : 2\r\n"
                    b"Content-Length: %d\r\n\r\n" % len(body) + body, 400,
                    "Content-Length :")
        b = refused(d, POST.encode() + b"Transfer-Encoding : chunked\r\n"
                    b"Content-Length: 2\r\n\r\n{}" + hidden, 400,
                    "Transfer-Encoding :")
        return a and b
    finally:
        d.stop()


def check_transfer_encoding(binary):
    """An unknown, doubled or padded Transfer-Encoding: 400 at once."""
    d = Daemon(binary, "--quiet")
    try:
        ok = True
        for te in (b"Transfer-Encoding: gzip\r\n",
                   b"Transfer-Encoding: chunked\r\n"
                   b"Transfer-Encoding: chunked\r\n",
                   b"Transfer-Encoding: chunked, chunked\r\n",
                   b"Transfer-Encoding: chunked \r\n",
                   b"Transfer-Encoding: xchunked\r\n"):
            ok = refused(d, POST.encode() + te + b"\r\n2\r\n{}\r\n0\r\n\r\n",
                         400, te.decode().strip()) and ok
        return ok
    finally:
        d.stop()


def check_chunk_over_limit(binary):
    """A chunk size of 2^64-1: 413 once the body is over the limit, not a
    wait for the chunk's end."""
    d = Daemon(binary, "--quiet", "--max-body", "65536")
    try:
        def more(s):
            s.sendall(b" " * 70000)
        raw, closed, dt = exchange(
            d.port, POST.encode() + b"Transfer-Encoding: chunked\r\n\r\n"
            b"ffffffffffffffff\r\n", keep_sending=more)
        ok = status_of(raw) == 413 and closed and dt < 2
        if not ok:
            print("  2^64-1: %r, closed %s, %.2f s" % (raw[:200], closed, dt))
        return ok
    finally:
        d.stop()


def check_chunk_extension(binary):
    """A chunk extension is read past (RFC 9112 7.1.1) while its chunk line
    (size and extensions) is at most 2048 bytes, even beside the largest
    header block the daemon takes; a longer line gets one 413 at once that
    names the limit, and a closed connection, where libmicrohttpd 0.9.75
    alone answers 500 to a line that does not fit the connection's memory
    (docs/howto/limits.md).  The access log has the status that was sent,
    not 499.  Content-Length bodies and chunk data are not read as lines,
    and each request on a connection is followed in turn."""
    d = Daemon(binary, "--no-jobs")
    head = (POST.replace("/simulate", "/stability").encode() +
            b"Transfer-Encoding: chunked\r\n")

    def chunked(line, rid, pad=0, close=True):
        """A request with a chunk line of @line bytes: its size 2 and an
        extension, then the chunk {}; @rid padded to 24 bytes, so that the
        header block's size is @pad's alone."""
        ext = b"2;x=" + b"a" * (line - 4)
        rid = rid.ljust(24, "-")
        return (head + (b"Connection: close\r\n" if close else b"") +
                (b"X-Pad: %s\r\n" % (b"p" * pad) if pad else b"") +
                b"X-Request-Id: %s\r\n\r\n" % rid.encode() + ext +
                b"\r\n{}\r\n0\r\n\r\n")

    def missing(raw):
        return status_of(raw) == 422 and b"/problems/missing-field" in raw

    try:
        ok = True
        # the largest X-Pad whose header block the daemon takes
        lo, hi = 0, 32768
        while hi - lo > 1:
            mid = (lo + hi) // 2
            raw, _, _ = exchange(d.port, chunked(10, "pad", mid), seconds=10)
            if status_of(raw) not in (413, 422):
                print("  X-Pad of %d: %r" % (mid, raw[:300]))
                return False
            if status_of(raw) == 413:
                hi = mid
            else:
                lo = mid
        for pad in (0, lo):
            raw, _, _ = exchange(d.port, chunked(2048, "at%d" % pad, pad))
            if not missing(raw):
                print("  a 2048-byte chunk line, X-Pad of %d: %r" %
                      (pad, raw[:300]))
                ok = False
        for line, pad in ((2049, 0), (2049, lo), (200000, 0)):
            rid = ("over%d-%d" % (line, pad)).ljust(24, "-")
            raw, closed, dt = exchange(d.port, chunked(line, rid, pad))
            heads = len(re.findall(rb"(?:^|\r\n)HTTP/1\.1 \d{3} ", raw))
            body = raw.partition(b"\r\n\r\n")[2]
            try:
                p = json.loads(body)
            except ValueError:
                p = {}
            if not (status_of(raw) == 413 and closed and dt < 2 and
                    heads == 1 and p.get("limit") == "max_chunk_line" and
                    p.get("limit_value") == 2048 and
                    b"X-Request-Id: " + rid.encode() in raw):
                print("  a chunk line of %d bytes, X-Pad of %d: closed %s, "
                      "%.2f s, %d status lines: %r" %
                      (line, pad, closed, dt, heads, raw[:400]))
                ok = False
            lines = d.log(lambda g: g.get("request_id") == rid)
            logged = [g["status"] for g in lines if g.get("request_id") ==
                      rid]
            if logged != [413]:
                print("  %s: logged %s" % (rid, logged))
                ok = False
        # on one connection: a Content-Length body of one long line, a chunk
        # of one long line, a short extension, then a line over the limit
        long_json = b'{"x":"' + b"b" * 9000 + b'"}'
        data = (POST.replace("/simulate", "/stability").encode() +
                b"Content-Length: %d\r\n\r\n" % len(long_json) + long_json +
                head + b"\r\n%x\r\n" % len(long_json) + long_json +
                b"\r\n0\r\n\r\n" +
                chunked(1000, "third", close=False) +
                chunked(3000, "fourth"))
        # at once, and in pieces of 701 bytes 2 ms apart, so that lines,
        # bodies and chunks are cut across the daemon's reads
        def pieces(sock):
            for k in range(0, len(data), 701):
                sock.sendall(data[k:k + 701])
                time.sleep(0.002)
        for how, first, more in (("at once", data, None),
                                 ("in pieces", b"", pieces)):
            raw, closed, dt = exchange(d.port, first, keep_sending=more)
            got = re.findall(rb"HTTP/1\.1 (\d{3}) ", raw)
            if got != [b"422", b"422", b"422", b"413"] or not closed:
                print("  four requests on a connection, %s: %s, closed %s, "
                      "%.2f s" % (how, got, closed, dt))
                ok = False
        return ok
    finally:
        d.stop()


def check_chunk_line_neighbours(binary):
    """What the daemon's reading of the bytes beside libmicrohttpd must not
    do: refuse a request the library reads otherwise (a line starting with
    NUL, which the library takes for an empty one, ends a trailer; the next
    request's Content-Length body then looks like a header block and an
    over-long chunk line), or cancel an earlier request still computing
    when a later one on the connection is refused."""
    d = Daemon(binary, "--no-jobs", *LONG_FLAGS)
    try:
        ok = True
        stab = POST.replace("/simulate", "/stability").encode()
        get = b"GET /health HTTP/1.1\r\nHost: x\r\n\r\n"
        body = b"x\r\nTransfer-Encoding: chunked\r\n\r\n" + b"A" * 2100
        data = (stab + b"Transfer-Encoding: chunked\r\n\r\n2\r\n{}\r\n0\r\n"
                b"\x00\r\n" + stab + b"Content-Length: %d\r\n\r\n" %
                len(body) + body + get)
        raw, _, _ = exchange(d.port, data, seconds=2)
        got = re.findall(rb"HTTP/1\.1 (\d{3}) ", raw)
        if got != [b"422", b"400", b"200"]:
            print("  a trailer ended by a NUL line: %s" % got)
            ok = False
        # about 0.2 s of computing, then a request refused behind it
        sim = ('{%s,"initial":%s,"t_end":5e6,"events":false}' %
               (PAPER, X0)).encode()
        data = (POST.encode() + b"Content-Length: %d\r\n\r\n" % len(sim) +
                sim + stab + b"Transfer-Encoding: chunked\r\n\r\n2;x=" +
                b"a" * 2100 + b"\r\n{}\r\n0\r\n\r\n")
        raw, closed, dt = exchange(d.port, data, seconds=10)
        got = re.findall(rb"HTTP/1\.1 (\d{3}) ", raw)
        if got != [b"200", b"413"] or not closed:
            print("  a computation, then a chunk line over the limit: %s, "
                  "closed %s, %.2f s" % (got, closed, dt))
            ok = False
        return ok
    finally:
        d.stop()


def check_header_block(binary):
    """A 32.5 KB header block gets a status line (413), not a bare close."""
    d = Daemon(binary, "--quiet")
    try:
        ok = True
        for n in (29000, 32500):
            ok = refused(d, b"GET /health HTTP/1.1\r\nHost: x\r\nX-Big: " +
                         b"a" * n + b"\r\n\r\n", 413, "%d B header" % n) and ok
        return ok
    finally:
        d.stop()


def check_header_block_once(binary):
    """Shapes that libmicrohttpd 0.9.75 answers with its header block twice
    (no Host) are answered by the daemon, once; and a space in the target."""
    d = Daemon(binary, "--quiet")
    try:
        a = refused(d, b"GET /health HTTP/1.1\r\nX-A: 1\r\n\r\n", 400,
                    "no Host")
        b = refused(d, b"GET /health HTTP/1.1\r\n Host: x\r\n\r\n", 400,
                    "folded Host")
        c = refused(d, b"GET /he alth HTTP/1.1\r\nHost: x\r\n\r\n", 400,
                    "space in the target")
        return a and b and c
    finally:
        d.stop()


def check_content_encoding(binary):
    """A gzip body: 415 naming the encoding, with Accept-Encoding."""
    d = Daemon(binary, "--quiet")
    try:
        body = b"\x1f\x8b\x08\x00\x00\x00\x00\x00"
        raw, _, _ = exchange(d.port, POST.encode() +
                             b"Content-Encoding: gzip\r\nConnection: close\r\n"
                             b"Content-Length: %d\r\n\r\n" % len(body) + body)
        head, _, text = raw.partition(b"\r\n\r\n")
        ok = (status_of(raw) == 415 and
              re.search(rb"\r\nAccept-Encoding: identity\r\n", head) and
              b"gzip" in text and b"identity" in text)
        if not ok:
            print("  gzip body: %r" % raw[:600])
        return bool(ok)
    finally:
        d.stop()


# ---- the access logs -------------------------------------------------------

def check_plain_log(binary):
    """The plain log escapes control characters: no forged line, no
    terminal escape."""
    d = Daemon(binary, "--log-format", "plain")
    try:
        for path in (b"/%0d%0aFAKE%20200%201", b"/%1b[31mred"):
            exchange(d.port, b"GET " + path +
                     b" HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
        exchange(d.port, b"GET /health HTTP/1.1\r\nHost: x\r\n"
                 b"Connection: close\r\n\r\n")
        end = time.time() + 5
        while not any("/health" in x for x in d.lines) and time.time() < end:
            time.sleep(0.05)
        text = "".join(d.lines)
        ok = (not any(x.startswith("FAKE") for x in d.lines) and
              "\x1b" not in text and "\r" not in text and
              "GET /\\x0d\\x0aFAKE\\x20200\\x201 404 " in text and
              "GET /\\x1b[31mred 404 " in text)
        if not ok:
            print("  plain log: %r" % text[-600:])
        return ok
    finally:
        d.stop()


def check_cut_stream(binary):
    """A batch whose client hangs up mid-answer is logged 499, not 200."""
    d = Daemon(binary, "--workers", "2", "--batch-parallel", "2",
               *LONG_FLAGS)
    try:
        body = json.dumps({"requests": [
            {"id": "short", "path": "/simulate", "body": json.loads(SHORT_SIM)},
            {"id": "long", "path": "/simulate", "body": json.loads(LONG_SIM)}]})
        s = socket.create_connection(("127.0.0.1", d.port))
        s.settimeout(10)
        s.sendall(b"POST /batch HTTP/1.1\r\nHost: x\r\nContent-Type: "
                  b"application/json\r\nContent-Length: %d\r\n\r\n" %
                  len(body) + body.encode())
        got = b""
        while b'"id":"short"' not in got:  # the first line is being sent
            k = s.recv(65536)
            if not k:
                break
            got += k
        s.close()
        lines = d.log(lambda g: g.get("path") == "/batch")
        st = [g["status"] for g in lines if g.get("path") == "/batch"]
        ok = status_of(got) == 200 and st == [499]
        if not ok:
            print("  cut batch: answered %s, logged %s" % (status_of(got), st))
        return ok
    finally:
        d.stop()


# ---- X-Forwarded-For -------------------------------------------------------

def check_forwarded(binary):
    """Behind a trusted proxy the client is the rightmost address a trusted
    proxy did not add, whatever the client wrote left of it."""
    d = Daemon(binary, "--trusted-proxy", "127.0.0.1")
    try:
        cases = [("203.0.113.%d, 198.51.100.7" % i, "198.51.100.7")
                 for i in (1, 2)]
        cases += [("forged, 198.51.100.8, 127.0.0.1", "198.51.100.8"),
                  ("198.51.100.9", "198.51.100.9"),
                  ("not-an-address", "127.0.0.1")]
        for i, (xff, _) in enumerate(cases):
            exchange(d.port, b"GET /health HTTP/1.1\r\nHost: x\r\n"
                     b"X-Request-Id: xff%d\r\nX-Forwarded-For: %s\r\n"
                     b"Connection: close\r\n\r\n" % (i, xff.encode()))
        last = "xff%d" % (len(cases) - 1)
        lines = d.log(lambda g: g.get("request_id") == last)
        seen = {g["request_id"]: g["client"] for g in lines}
        ok = True
        for i, (xff, want) in enumerate(cases):
            if seen.get("xff%d" % i) != want:
                print("  X-Forwarded-For %r: client %s, want %s" %
                      (xff, seen.get("xff%d" % i), want))
                ok = False
        return ok
    finally:
        d.stop()


# ---- metrics ---------------------------------------------------------------

def metrics(d):
    with urllib.request.urlopen(d.url + "/metrics", timeout=10) as r:
        return r.read().decode()


def value(text, series):
    m = re.search(r"^%s (\S+)$" % re.escape(series), text, re.M)
    return float(m.group(1)) if m else None


def queued_by(text):
    """stickslip_queued_requests by endpoint: every endpoint that computes is
    there (orbit, stability, map, batch, jobs...); the nonzero ones, and
    simulate's whatever it is."""
    got = {k: int(v) for k, v in re.findall(
        r'^stickslip_queued_requests\{endpoint="([^"]*)"\} (\d+)$', text,
        re.M)}
    want = {"orbit", "simulate", "stability", "continue", "map", "basins",
            "batch", "jobs"}
    if not want <= set(got) or "health" in got:
        return {"series": sorted(got)}
    return {k: v for k, v in got.items() if v or k == "simulate"}


def check_metrics(binary):
    """Busy workers, the queue and what it holds by endpoint, batch items by
    path and status, and buckets up to a minute: present, and moving."""
    d = Daemon(binary, "--quiet", "--workers", "1", "--client-workers", "1",
               *LONG_FLAGS)
    try:
        before = metrics(d)
        ok = (value(before, "stickslip_workers_busy") == 0 and
              value(before, "stickslip_workers") == 1 and
              value(before, "stickslip_queued") == 0 and
              'le="60"' in before and 'le="2.5"' in before)
        ok = queued_by(before) == {"simulate": 0} and ok
        long_c = []
        # one runs, one waits, and a cheap /stability waits behind them
        for path, body in (("/simulate", LONG_SIM), ("/simulate", LONG_SIM),
                           ("/stability", "{}")):
            s = socket.create_connection(("127.0.0.1", d.port))
            s.sendall(POST.replace("/simulate", path).encode() +
                      b"Content-Length: %d\r\n\r\n" % len(body) +
                      body.encode())
            long_c.append(s)
        end, busy = time.time() + 10, None
        while time.time() < end:
            busy = metrics(d)
            if (value(busy, "stickslip_workers_busy") == 1 and
                    value(busy, "stickslip_queued") == 2):
                break
            time.sleep(0.05)
        ok = (value(busy, "stickslip_workers_busy") == 1 and
              value(busy, "stickslip_queued") == 2 and
              value(busy, "stickslip_queued_clients") == 1 and
              queued_by(busy) == {"simulate": 1, "stability": 1}) and ok
        for s in long_c:
            s.close()
        body = json.dumps({"requests": [
            {"path": "/simulate", "body": json.loads(SHORT_SIM)},
            {"path": "/simulate", "body": json.loads(SHORT_SIM)},
            {"path": "/simulate", "body": {"params": {}}},
            {"path": "/nowhere", "body": {}}]}).encode()
        req = urllib.request.Request(d.url + "/batch", data=body,
                                     headers={"Content-Type":
                                              "application/json"})
        with urllib.request.urlopen(req, timeout=60) as r:
            r.read()
        after = metrics(d)
        items = dict(re.findall(
            r'^stickslip_batch_items_total\{(endpoint="[^"]*",code="\d+")\} '
            r"(\d+)$", after, re.M))
        ok = (queued_by(after) == {"simulate": 0} and
              items.get('endpoint="simulate",code="200"') == "2" and
              items.get('endpoint="simulate",code="422"') == "1" and
              items.get('endpoint="other",code="404"') == "1") and ok
        if not ok:
            print("  metrics: busy %s queued %s (%s; before %s, after %s), "
                  "items %s" %
                  (value(busy, "stickslip_workers_busy"),
                   value(busy, "stickslip_queued"), queued_by(busy),
                   queued_by(before), queued_by(after), items))
        return ok
    finally:
        d.stop()


CHECKS = {name[len("check_"):]: f for name, f in sorted(globals().items())
          if name.startswith("check_")}


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    names = sys.argv[2:] or list(CHECKS)
    failed = []
    for name in names:
        ok = CHECKS[name](sys.argv[1])
        print("%s: %s" % (name, "ok" if ok else "FAILED"))
        if not ok:
            failed.append(name)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
