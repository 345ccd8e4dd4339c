"""What the job checks over HTTP share (check_replicas.py,
check_job_answers.py): a check that records its failures, one request on
its own connection, a daemon started on an ephemeral port, the PostgreSQL
URI the CTest fixture pg writes, and the exit status."""
import http.client
import json
import re
import subprocess
import sys

PAPER = {"chi": 0.2, "eta": 4, "us": 0.0724, "ur": 0.6178, "V": 1}
FAILURES = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        FAILURES.append(what)


def call(port, method, path, body=None, headers=None, timeout=600):
    """(status, headers, text) of one request with a JSON body."""
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    h = {"Content-Type": "application/json"}
    h.update(headers or {})
    c.request(method, path, None if body is None else json.dumps(body), h)
    r = c.getresponse()
    data = r.read().decode()
    c.close()
    return r.status, dict(r.getheaders()), data


def start(daemon, *args):
    """A daemon on a port of its own choosing, quiet: (process, port)."""
    p = subprocess.Popen([daemon, "--port", "0", "--quiet", *args],
                         stderr=subprocess.PIPE, stdout=subprocess.DEVNULL,
                         text=True)
    line = p.stderr.readline()
    m = re.search(r":(\d+)$", line.strip())
    if not m:
        p.kill()
        sys.exit("the daemon did not start: " + line)
    return p, int(m.group(1))


def pg_uri(arg):
    """The URI in the file @FILE names (the fixture pg's), or None, said
    so, when there is none: the caller skips (77)."""
    try:
        with open(arg.lstrip("@")) as f:
            return f.read().strip()
    except OSError:
        print("no PostgreSQL (%s unreadable): skipped" % arg)
        return None


def outcome():
    """The exit status: 1 with the failures counted, else 0."""
    if FAILURES:
        print("%d failures" % len(FAILURES))
        return 1
    return 0
