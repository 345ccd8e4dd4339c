#!/usr/bin/env python3
"""The daemon as a process its operator runs: one check per CTest.

  notify      systemd's readiness protocol (a unit of Type=notify): with
              NOTIFY_SOCKET naming a datagram socket this test binds (a
              path, then an abstract name, '@...'), the daemon sends
              READY=1 with its URL once it answers, and STOPPING=1 on
              SIGTERM before it drains; it exits 0.  A socket nobody
              listens on is said on stderr and the daemon serves on.

Usage: check_daemon.py STICKSLIPD CHECK
"""
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import urllib.request

DAEMON = None


def fail(msg):
    sys.exit("check_daemon: " + msg)


def start(args, env=None):
    """The daemon started with @a args (on a free port unless they name
    one), and the URL it prints when it listens."""
    p = subprocess.Popen([DAEMON, "--quiet", "--no-jobs"] + args,
                         env=dict(os.environ, **(env or {})),
                         stderr=subprocess.PIPE, stdout=subprocess.DEVNULL,
                         text=True)
    line = p.stderr.readline()
    m = re.search(r"listening on (http://\S+)", line)
    if not m:
        p.kill()
        fail("the daemon did not start: " + line + p.stderr.read())
    return p, m.group(1)


def stop(p):
    p.send_signal(signal.SIGTERM)
    rest = p.stderr.read()
    if p.wait(timeout=60) != 0:
        fail("the daemon exited %d: %s" % (p.returncode, rest))
    return rest


def states(sock):
    """The variables of the next datagram on @a sock."""
    data = sock.recv(4096).decode()
    return dict(line.split("=", 1) for line in data.split("\n") if line)


def check_notify():
    with tempfile.TemporaryDirectory() as tmp:
        for name in (os.path.join(tmp, "notify"),
                     "@stickslip-check-notify-%d" % os.getpid()):
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
            sock.bind("\0" + name[1:] if name[0] == "@" else name)
            sock.settimeout(60)
            p, url = start(["--port", "0"], {"NOTIFY_SOCKET": name})
            got = states(sock)
            if got.get("READY") != "1" or url not in got.get("STATUS", ""):
                fail("%s: not READY=1 with the URL %s: %s" % (name, url, got))
            # ready means it answers
            with urllib.request.urlopen(url + "/health", timeout=30) as r:
                if r.status != 200:
                    fail("%s: /health answered %d after READY=1" %
                         (name, r.status))
            p.send_signal(signal.SIGTERM)
            got = states(sock)
            if got.get("STOPPING") != "1" or "draining" not in got.get(
                    "STATUS", ""):
                fail("%s: not STOPPING=1 on SIGTERM: %s" % (name, got))
            stop(p)
            sock.close()
            print("notify: %s: READY=1, STOPPING=1" % name)
        # a manager that is not there: said, and the daemon serves on
        p, url = start(["--port", "0"],
                       {"NOTIFY_SOCKET": os.path.join(tmp, "nobody")})
        with urllib.request.urlopen(url + "/health", timeout=30) as r:
            ok = r.status == 200
        err = stop(p)
        if not ok or "cannot notify" not in err:
            fail("a NOTIFY_SOCKET nobody reads: %s" % err)
        print("notify: a socket nobody reads is said, the daemon serves")


CHECKS = {"notify": check_notify}


def main():
    global DAEMON
    if len(sys.argv) != 3 or sys.argv[2] not in CHECKS:
        sys.exit(__doc__)
    DAEMON = sys.argv[1]
    CHECKS[sys.argv[2]]()


if __name__ == "__main__":
    main()
