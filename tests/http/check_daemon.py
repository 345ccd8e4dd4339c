#!/usr/bin/env python3
"""The daemon as a process its operator runs: one check per CTest.

  notify      systemd's readiness protocol (a unit of Type=notify): with
              NOTIFY_SOCKET naming a datagram socket this test binds (a
              path, then an abstract name, '@...'), the daemon sends
              READY=1 with its URL once it answers, and STOPPING=1 on
              SIGTERM before it drains; it exits 0.  A socket nobody
              listens on is said on stderr and the daemon serves on.
  port_taken  a daemon started on the port of another says so in one line
              that names the way out (--port N, STICKSLIP_PORT, --port 0),
              and exits 3, as the man page's EXIT STATUS says.
  help        every option the daemon parses (each "--..." literal of
              server/main.c) is in --help and in the man page's OPTIONS,
              and each of those names only options it parses; the man page
              has EXAMPLES, EXIT STATUS and FILES; each default --help
              prints is a value its flag takes.
  fd_limit    a hard descriptor limit too low for --max-connections is
              said on stderr after the URL; one high enough is not.
  environment a bad value in a STICKSLIP_ variable stops the daemon with
              exit 2 and a message naming the variable.

Usage: check_daemon.py STICKSLIPD CHECK
"""
import os
import re
import resource
import signal
import socket
import subprocess
import sys
import tempfile
import urllib.request

DAEMON = None
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))))


def fail(msg):
    sys.exit("check_daemon: " + msg)


def start(args, env=None, fds=None):
    """The daemon started with @a args (on a free port unless they name
    one), under a descriptor limit of @a fds when given, and the URL it
    prints when it listens."""
    def limit():
        resource.setrlimit(resource.RLIMIT_NOFILE, (fds, fds))
    p = subprocess.Popen([DAEMON, "--quiet", "--no-jobs"] + args,
                         env=dict(os.environ, **(env or {})),
                         stderr=subprocess.PIPE, stdout=subprocess.DEVNULL,
                         text=True, preexec_fn=limit if fds else None)
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


def check_port_taken():
    p, url = start(["--port", "0"])
    port = url.rsplit(":", 1)[1]
    try:
        for args, env in ((["--port", port], {}),
                          ([], {"STICKSLIP_PORT": port})):
            q = subprocess.run([DAEMON, "--no-jobs"] + args,
                               env=dict(os.environ, **env),
                               capture_output=True, text=True, timeout=60)
            lines = q.stderr.splitlines()
            if q.returncode != 3 or len(lines) != 1:
                fail("port taken (%s %s): exit %d, %r" %
                     (args, env, q.returncode, q.stderr))
            for way in ("--port N", "STICKSLIP_PORT", "--port 0", port):
                if way not in lines[0]:
                    fail("port taken: %r does not name %s" % (lines[0], way))
            print("port_taken: exit 3, " + lines[0])
    finally:
        stop(p)
    man = open(os.path.join(ROOT, "packaging", "stickslipd.1")).read()
    status = man.split(".SH EXIT STATUS", 1)[-1].split(".SH", 1)[0]
    if not re.search(r"^3$", status, re.M) or "taken" not in status:
        fail("the man page's EXIT STATUS does not give 3 for a port taken")


def flags_of_man(man):
    """The options of the man page's OPTIONS section."""
    opts = man.split(".SH OPTIONS", 1)[1].split(".SH", 1)[0]
    return set("--" + f.replace("\\-", "-") for f in
               re.findall(r"^\\fB\\-\\-([a-z\\-]+)\\fR", opts, re.M))


def check_help():
    src = open(os.path.join(ROOT, "server", "main.c")).read()
    parsed = set(re.findall(r'"(--[a-z][a-z-]*)"', src))
    q = subprocess.run([DAEMON, "--help"], capture_output=True, text=True,
                       timeout=60)
    if q.returncode != 0:
        fail("--help exited %d" % q.returncode)
    helped = set(re.findall(r"^  (--[a-z][a-z-]*)", q.stdout, re.M))
    man = open(os.path.join(ROOT, "packaging", "stickslipd.1")).read()
    manned = flags_of_man(man)
    if len(parsed) < 40:
        fail("only %d options found in server/main.c" % len(parsed))
    for name, got in (("--help", helped), ("the man page", manned)):
        if parsed - got:
            fail("%s lacks %s" % (name, ", ".join(sorted(parsed - got))))
        if got - parsed:
            fail("%s names %s, which the daemon does not parse" %
                 (name, ", ".join(sorted(got - parsed))))
    for section in ("EXAMPLES", "EXIT STATUS", "FILES"):
        if ".SH " + section not in man:
            fail("the man page has no " + section)
    # each default --help prints is a value its flag takes
    entries = re.split(r"^  (?=--)", q.stdout.split("\n\n", 2)[-1], flags=re.M)
    defaults = {}
    for e in entries:
        m = re.match(r"(--[a-z-]+) [A-Z]+\s.*\(([-+0-9.e]+)\)\s*$", e, re.S)
        if m:
            defaults[m.group(1)] = m.group(2)
    if len(defaults) < 25:
        fail("only %d defaults found in --help" % len(defaults))
    for flag, value in sorted(defaults.items()):
        r = subprocess.run([DAEMON, flag, value, "--help"], capture_output=True,
                           text=True, timeout=60)
        if r.returncode != 0:
            fail("--help gives %s the default %s, which it refuses: %s" %
                 (flag, value, r.stderr.strip()))
    print("help: %d options, each in --help and the man page; %d defaults, "
          "each taken by its flag" % (len(parsed), len(defaults)))


def check_fd_limit():
    """Under a hard descriptor limit too low for --max-connections the
    daemon serves, and says so after its URL, naming the way out; with
    enough it says nothing."""
    for fds, conns, said in ((300, 2048, True), (300, 200, False)):
        p, url = start(["--port", "0", "--max-connections", str(conns)],
                       fds=fds)
        with urllib.request.urlopen(url + "/health", timeout=30) as r:
            if r.status != 200:
                fail("/health answered %d" % r.status)
        rest = stop(p)
        told = ("descriptor limit is %d, too few for --max-connections %d"
                % (fds, conns)) in rest and "LimitNOFILE=" in rest
        if told != said or ("descriptor limit" in rest) != said:
            fail("limit %d, --max-connections %d: stderr %r" %
                 (fds, conns, rest))
    print("fd_limit: a limit too low is said, one high enough is not")


def check_environment():
    """A bad value in a variable stops the daemon (exit 2, as a bad option)
    with a message that names the variable: a number, a text, a list item,
    a list too long to hold."""
    bad = {"STICKSLIP_MAX_SECONDS": "-1",
           "STICKSLIP_LOG_FORMAT": "xml",
           "STICKSLIP_JOB_STORE": "x" * 5000,
           "STICKSLIP_STATE_DIR": "x" * 5000,
           "STICKSLIP_TRUSTED_PROXY": "10.0.0.1,nonsense",
           "STICKSLIP_CORS_ORIGIN": "http://a:3000,not-an-origin"}
    # a list longer than the daemon holds is refused, not cut (a cut could
    # leave 10.0.0.1 of 10.0.0.12)
    long_list = ",".join(["10.0.0.12"] * 120)
    cases = list(bad.items()) + [("STICKSLIP_TRUSTED_PROXY", long_list)]
    for name, value in cases:
        env = {k: v for k, v in os.environ.items()
               if not k.startswith("STICKSLIP_")}
        env[name] = value
        r = subprocess.run([DAEMON, "--port", "0", "--no-jobs"], env=env,
                           capture_output=True, text=True, timeout=60)
        if r.returncode != 2 or name not in r.stderr:
            fail("%s=%s...: exit %d, %r" % (name, value[:20], r.returncode,
                                            r.stderr))
    print("environment: %d bad values, each refused naming its variable" %
          len(cases))


CHECKS = {"notify": check_notify, "port_taken": check_port_taken,
          "help": check_help, "fd_limit": check_fd_limit,
          "environment": check_environment}


def main():
    global DAEMON
    if len(sys.argv) != 3 or sys.argv[2] not in CHECKS:
        sys.exit(__doc__)
    DAEMON = sys.argv[1]
    CHECKS[sys.argv[2]]()


if __name__ == "__main__":
    main()
