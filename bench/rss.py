#!/usr/bin/env python3
"""The daemon's resident memory (RSS, from /proc) while clients that never
read their answers hold it, and after they have gone.

    rss.py STICKSLIPD [--check SCENARIO CLIENTS] [--out FILE]

Each scenario starts a daemon of its own (--quiet, on port 0) and reads its
RSS idle; then CLIENTS connections, each from a small receive buffer, send
one request whose answer is megabytes and never read it, again on half of
them once the first answers are held (a second round, so that memory freed
by the first is reused, not added to); the peak is the largest VmRSS read
every 20 ms until the memory budget's bytes stop moving, and VmHWM at the
end.  Then every client closes, and "after" is VmRSS once the budget's
bytes are back to 0 and two seconds have passed.

Without --check: every scenario (/batch, /simulate with samples, /map,
/basins; gzip on and off) at 256 and 1000 clients, a Markdown table on
stdout and into FILE (default bench/results/rss.md).
With --check: that one scenario; exit 1 unless the peak stays under 300 MB
and "after" within 50 MB of idle (the bounds the README states).
"""
import os
import re
import socket
import subprocess
import sys
import time
import urllib.request

PAPER = '"params":{"chi":0.2,"eta":4,"us":0.0724,"ur":0.6178,"V":1}'
X0 = "[1.2739277342427042,4.362927734242703,-0.8074871367243053,1.0]"
GUESS = '{%s,"guess":{"durations":[4.5,2.717,3.0536]},"finite_difference":false}' % PAPER

# Each body's answer is a few megabytes.
BODIES = {
    # 2000 /orbit items from a guess: 3.8 MB of lines
    "batch": '{"requests":[%s]}' % ",".join(
        ['{"path":"/orbit","body":%s}' % GUESS] * 2000),
    # 100 000 samples: 4.3 MB, streamed
    "simulate": '{%s,"initial":%s,"t_end":10000,"samples":{"n":100000}}' % (
        PAPER, X0),
    # 30 cells, each with its orbits: about 0.3 MB of lines
    "map": '{%s,"axes":[{"parameter":"ur","from":0.55,"to":0.75,"n":30}],'
           '"kind":"overshoot"}' % PAPER,
    # 64 x 64 starts: their attractors and times
    "basins": '{%s,"axes":[{"variable":"x1","from":-2,"to":4,"n":64},'
              '{"variable":"x2","from":0,"to":8,"n":64}],'
              '"state":{"v1":0,"v2":1}}' % PAPER,
}
PATHS = {"batch": "/batch", "simulate": "/simulate", "map": "/map",
         "basins": "/basins"}
PEAK_MB, AFTER_MB = 300, 50


def status_kb(pid, field):
    with open("/proc/%d/status" % pid) as f:
        m = re.search(r"^%s:\s+(\d+) kB" % field, f.read(), re.M)
    return int(m.group(1)) if m else 0


def held(port, series="stickslip_memory_held_bytes"):
    """The bytes the memory budget counts (or another series); -1 when the
    daemon does not answer."""
    try:
        with urllib.request.urlopen("http://127.0.0.1:%d/metrics" % port,
                                    timeout=10) as r:
            m = re.search(rb"^%s (\S+)$" % series.encode(), r.read(), re.M)
        return float(m.group(1)) if m else -1
    except OSError:
        return -1


def request(path, body, gzip):
    return (b"POST %s HTTP/1.1\r\nHost: x\r\nContent-Type: application/json"
            b"\r\n%sContent-Length: %d\r\n\r\n" %
            (path.encode(), b"Accept-Encoding: gzip\r\n" if gzip else b"",
             len(body)) + body)


def client(port, req, k):
    """Connection @k, which sends @req and never reads (4 KiB of receive
    buffer: the answer stays in the daemon); 200 from each loopback
    address, under the daemon's limit per address."""
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.settimeout(10)
    s.bind(("127.0.1.%d" % (1 + k // 200), 0))
    s.connect(("127.0.0.1", port))
    s.sendall(req)
    return s


class Peak:
    """The largest VmRSS seen."""

    def __init__(self, pid):
        self.pid, self.kb = pid, 0

    def read(self):
        self.kb = max(self.kb, status_kb(self.pid, "VmRSS"))


def settle(port, peak, seconds):
    """Until the bytes the budget counts have not moved for a second (the
    answers are held, or the pool idles), reading the peak."""
    last, since, end = None, time.time(), time.time() + seconds
    while time.time() < end:
        h = held(port)
        peak.read()
        if h != last:
            last, since = h, time.time()
        elif time.time() - since > 1.0:
            break
        time.sleep(0.02)


def run(binary, scenario, clients, gzip, flags=()):
    """(idle MB, peak MB, after MB, peak MiB the budget counted) of one
    scenario."""
    p = subprocess.Popen(
        [binary, "--port", "0", "--quiet", "--no-jobs",
         "--connection-timeout", "120", *flags],
        stderr=subprocess.PIPE, text=True, errors="replace")
    socks = []
    try:
        m = re.search(r"http://[^ \n]+:(\d+)", p.stderr.readline())
        if not m:
            sys.exit("rss.py: the daemon did not start")
        port = int(m.group(1))
        held(port)
        time.sleep(0.5)
        idle = status_kb(p.pid, "VmRSS")
        peak = Peak(p.pid)
        req = request(PATHS[scenario], BODIES[scenario].encode(), gzip)
        for rnd in range(2):
            for k in range(clients if rnd == 0 else clients // 2):
                if rnd:
                    socks[k].close()
                    socks[k] = client(port, req, k)
                else:
                    socks.append(client(port, req, k))
                if k % 16 == 0:
                    peak.read()
            settle(port, peak, 120)
        for s in socks:
            s.close()
        socks = []
        end = time.time() + 60
        while time.time() < end and held(port) != 0:
            peak.read()
            time.sleep(0.05)
        time.sleep(2)
        peak.read()
        after = status_kb(p.pid, "VmRSS")
        hwm = status_kb(p.pid, "VmHWM")
        counted = held(port, "stickslip_memory_held_peak_bytes") / 1048576
        return idle / 1024, max(peak.kb, hwm) / 1024, after / 1024, counted
    finally:
        for s in socks:
            s.close()
        p.terminate()
        p.wait(30)


def row(binary, scenario, clients, gzip):
    idle, peak, after, counted = run(binary, scenario, clients, gzip)
    ok = peak < PEAK_MB and after - idle < AFTER_MB
    line = "| %s | %d | %s | %.1f | %.1f | %.1f | %.1f | %s |" % (
        PATHS[scenario], clients, "gzip" if gzip else "identity", idle, peak,
        counted, after, "yes" if ok else "NO")
    print(line, flush=True)
    return line, ok


def main():
    args = sys.argv[1:]
    if not args:
        sys.exit(__doc__)
    binary = args[0]
    if "--check" in args:
        k = args.index("--check")
        scenario, clients = args[k + 1], int(args[k + 2])
        gzip = "--gzip" in args
        _, ok = row(binary, scenario, clients, gzip)
        sys.exit(0 if ok else 1)
    out = "bench/results/rss.md"
    if "--out" in args:
        out = args[args.index("--out") + 1]
    head = ["# Resident memory under clients that do not read",
            "",
            "Generated by `bench/rss.py`: for each row a fresh Release "
            "stickslipd (default",
            "budget, %d cores); the clients send, never read, send again on "
            "half of the" % os.cpu_count(),
            "connections, then all close.  MB of VmRSS (peak: also VmHWM) "
            "from /proc;",
            "the budget's peak: what the daemon counted against "
            "--memory-budget.",
            "Bound: peak under %d MB, after within %d MB of idle." % (
                PEAK_MB, AFTER_MB),
            "",
            "| path | clients | encoding | idle | peak | budget's peak (MiB) "
            "| after | within |",
            "| --- | ---: | --- | ---: | ---: | ---: | ---: | --- |"]
    lines = []
    for scenario in ("batch", "simulate", "map", "basins"):
        for clients in (256, 1000):
            for gzip in (False, True):
                lines.append(row(binary, scenario, clients, gzip)[0])
    with open(out, "w") as f:
        f.write("\n".join(head + lines) + "\n")
    print("wrote", out)


if __name__ == "__main__":
    main()
