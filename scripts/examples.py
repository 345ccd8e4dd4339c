#!/usr/bin/env python3
"""The examples of the README, the user's guide and the contract, against a
live daemon.

  python3 scripts/examples.py --check STICKSLIPD   (what CI runs)
  python3 scripts/examples.py --write STICKSLIPD   (regenerate them)

Starts STICKSLIPD on a free port, then
  - README.md and every page of docs/: every ```sh block that is a curl
    command followed by a fenced output block: the command is run against
    the daemon and its answer compared with the block (JSON or NDJSON,
    numbers to a relative 1e-9, the keys that change from run to run left
    out: seconds, uptime_seconds, a request_id the request did not set);
  - api/openapi.json: every request example of a POST is sent, and the
    response example of the same name compared the same way.
--check fails (exit 1) on the first difference and says where; --write
puts the daemon's answers in place (the pages' as the daemon prints them,
the contract's as JSON values or NDJSON text).  Standard library only.
"""
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import urllib.error
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAGES = [os.path.join(ROOT, "README.md")] + sorted(
    os.path.join(d, f) for d, _, fs in os.walk(os.path.join(ROOT, "docs"))
    for f in fs if f.endswith(".md"))
SPEC = os.path.join(ROOT, "api", "openapi.json")
VOLATILE = {"seconds", "uptime_seconds", "in_flight"}


def start(binary, state):
    p = subprocess.Popen([binary, "--port", "0", "--quiet", "--state-dir",
                          state], stderr=subprocess.PIPE, text=True)
    line = p.stderr.readline()
    m = re.search(r"http://[^ \n]+", line)
    if not m:
        p.kill()
        sys.exit("examples: the daemon did not start: " + line)
    return p, m.group(0).rstrip("/")


def request(base, method, path, body=None, headers=None):
    h = dict(headers or {})
    data = body.encode() if body is not None else None
    req = urllib.request.Request(base + path, data=data, method=method,
                                 headers=h)
    try:
        with urllib.request.urlopen(req, timeout=120) as r:
            return r.status, r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, e.read().decode()


def curl(base, command):
    """Run a page's curl command (-s, -H, -d, -X, a URL) with urllib."""
    args = shlex.split(command.replace("\\\n", " "))
    if not args or args[0] != "curl":
        return None
    method, body, headers, url = None, None, {}, None
    i = 1
    while i < len(args):
        a = args[i]
        if a in ("-s", "-S", "-sS", "--silent", "-si", "-i", "-sN", "-N"):
            pass  # silent, headers shown, no buffering: the same answer
        elif a in ("-H", "--header"):
            k, v = args[i + 1].split(":", 1)
            headers[k.strip()] = v.strip()
            i += 1
        elif a in ("-d", "--data", "--data-binary"):
            body = args[i + 1]
            i += 1
        elif a in ("-X", "--request"):
            method = args[i + 1]
            i += 1
        elif a.startswith("http"):
            url = a
        else:
            raise ValueError("examples: a curl option it does not know: " + a)
        i += 1
    path = re.sub(r"^https?://[^/]+", "", url)
    return request(base, method or ("POST" if body is not None else "GET"),
                   path, body, headers)


def normal(text, keep_id):
    """JSON or NDJSON text as a comparable value."""
    def clean(v):
        if isinstance(v, dict):
            return {k: clean(x) for k, x in v.items()
                    if k not in VOLATILE and (keep_id or k != "request_id")}
        if isinstance(v, list):
            return [clean(x) for x in v]
        return v
    text = text.strip()
    try:
        return clean(json.loads(text))
    except ValueError:
        lines = [clean(json.loads(l)) for l in text.splitlines() if l.strip()]
        # a batch's items come in the order they are done
        return sorted(lines, key=lambda l: (0, l["index"]) if isinstance(
            l.get("index"), int) else (1, 0))


def same(a, b, where="", rtol=1e-9):
    if isinstance(a, bool) or isinstance(b, bool):
        return None if a == b else where + ": %r != %r" % (a, b)
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        if abs(a - b) <= rtol * max(1.0, abs(a), abs(b)):
            return None
        return where + ": %r != %r" % (a, b)
    if type(a) != type(b):
        return where + ": types differ"
    if isinstance(a, dict):
        if set(a) != set(b):
            return where + ": keys differ: %s" % sorted(set(a) ^ set(b))
        for k in a:
            d = same(a[k], b[k], where + "/" + k, rtol)
            if d:
                return d
        return None
    if isinstance(a, list):
        if len(a) != len(b):
            return where + ": lengths %d != %d" % (len(a), len(b))
        for i, (x, y) in enumerate(zip(a, b)):
            d = same(x, y, "%s/%d" % (where, i), rtol)
            if d:
                return d
        return None
    return None if a == b else where + ": %r != %r" % (a, b)


FENCE = re.compile(r"^```([a-z]*)\n(.*?)^```\n", re.S | re.M)


def page(base, name, write):
    text = open(name).read()
    blocks = list(FENCE.finditer(text))
    out, last, checked = [], 0, 0
    rel = os.path.relpath(name, ROOT)
    for i, b in enumerate(blocks):
        if b.group(1) != "sh" or not b.group(2).lstrip().startswith("curl"):
            continue
        line = text[:b.start()].count("\n") + 2
        nxt = blocks[i + 1] if i + 1 < len(blocks) else None
        if not nxt or nxt.group(1) not in ("json", ""):
            # no answer shown: each command of the block must succeed
            for cmd in re.split(r"(?<!\\)\n", b.group(2).strip()):
                cmd = re.sub(r"\s+#.*$", "", cmd)
                if not cmd.startswith("curl") or "<" in cmd:
                    continue
                status, _ = curl(base, cmd)
                checked += 1
                if not 200 <= status < 300:
                    print("%s:%d: the daemon answered %d" % (rel, line, status))
                    return checked, False
            continue
        keep_id = "X-Request-Id" in b.group(2)
        want = nxt.group(2)
        try:
            want_v = normal(want, keep_id) if want.strip() else None
        except ValueError:
            continue  # not an answer (a shell session, a sketch)
        answer = curl(base, b.group(2).strip())[1]
        d = same(want_v, normal(answer, keep_id)) if want_v is not None \
            else "no answer written yet"
        checked += 1
        if d and not write:
            line = text[:nxt.start()].count("\n") + 2
            print("%s:%d: the answer differs at %s" % (rel, line, d))
            return checked, False
        if d and write:
            out.append(text[last:nxt.start(2)])
            out.append(answer.strip() + "\n")
            last = nxt.end(2)
    if write:
        out.append(text[last:])
        open(name, "w").write("".join(out))
    return checked, True


def spec(base, write):
    doc = json.load(open(SPEC))
    checked = 0
    for path, item in doc["paths"].items():
        post = item.get("post")
        if not post:
            continue
        reqs = (post.get("requestBody", {}).get("content", {})
                .get("application/json", {}).get("examples", {}))
        for name, ex in reqs.items():
            # each answer example of that name, asked in its media type
            found = [(code, mt, media["examples"][name])
                     for code, resp in post.get("responses", {}).items()
                     for mt, media in resp.get("content", {}).items()
                     if name in media.get("examples", {})]
            if not found:
                print("openapi.json: %s %s has no response example" %
                      (path, name))
                return checked, False
            for code, mt, rex in found:
                status, answer = request(base, "POST", path,
                                         json.dumps(ex["value"]),
                                         {"Content-Type": "application/json",
                                          "Accept": mt})
                want = rex["value"]
                got_v = normal(answer, False)
                want_v = normal(want, False) if isinstance(want, str) else \
                    normal(json.dumps(want), False)
                d = None if str(status) == code else \
                    "status %d != %s" % (status, code)
                d = d or same(want_v, got_v)
                checked += 1
                if d and not write:
                    print("openapi.json: %s example %s differs: %s" %
                          (path, name, d))
                    return checked, False
                if d and write:
                    rex["value"] = answer if isinstance(want, str) else \
                        json.loads(answer)
    if write:
        open(SPEC, "w").write(json.dumps(doc, indent=2) + "\n")
    return checked, True


def main():
    if len(sys.argv) != 3 or sys.argv[1] not in ("--check", "--write"):
        sys.exit(__doc__)
    write = sys.argv[1] == "--write"
    state = tempfile.mkdtemp(prefix="stickslip-examples-")
    proc, base = start(sys.argv[2], state)
    try:
        n1, ok1 = 0, True
        for name in PAGES:
            n, ok1 = page(base, name, write)
            n1 += n
            if not ok1:
                break
        n2, ok2 = spec(base, write) if ok1 else (0, False)
    finally:
        proc.terminate()
        proc.wait()
        shutil.rmtree(state, ignore_errors=True)
    print("examples: %d in README.md and docs/, %d in api/openapi.json %s" %
          (n1, n2, "written" if write else "checked" if ok1 and ok2
           else "- differ"))
    sys.exit(0 if ok1 and ok2 else 1)


if __name__ == "__main__":
    main()
