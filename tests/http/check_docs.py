#!/usr/bin/env python3
"""The daemon serves the user's guide at /docs/ (README "The user's guide").

  check_docs.py STICKSLIPD built|none

built: every page, style sheet, script and picture that the guide's pages
link to is answered 200 with its media type, the same bytes twice, a
validator that gives 304; a page that is not there, /docs without its slash
and a POST are problems (404, 404, 405).  none (a build without mkdocs):
/docs/ is a 404 problem that says the guide was not built.
"""
import html.parser
import json
import posixpath
import re
import subprocess
import sys
import urllib.error
import urllib.parse
import urllib.request


def start(binary):
    p = subprocess.Popen([binary, "--port", "0", "--quiet", "--no-jobs"],
                         stderr=subprocess.PIPE, text=True)
    m = re.search(r"http://[^ \n]+", p.stderr.readline())
    if not m:
        p.kill()
        sys.exit("check_docs: the daemon did not start")
    return p, m.group(0).rstrip("/")


def get(url, method="GET", headers=None):
    req = urllib.request.Request(url, method=method, headers=headers or {})
    try:
        with urllib.request.urlopen(req, timeout=30) as r:
            return r.status, r.headers, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.headers, e.read()


class Refs(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.refs = []

    def handle_starttag(self, tag, attrs):
        for k, v in attrs:
            if k in ("href", "src") and v:
                self.refs.append(v)


def fail(msg):
    print("check_docs: " + msg)
    sys.exit(1)


def problem(base, path, status, method="GET", says=None):
    code, h, body = get(base + path, method)
    if code != status or h.get("Content-Type") != "application/problem+json":
        fail("%s %s: %d %s, not a %d problem" % (method, path, code,
                                                 h.get("Content-Type"), status))
    detail = json.loads(body)["detail"]
    if says and says not in detail:
        fail("%s: the problem says %r" % (path, detail))


def crawl(base):
    """Every file reachable from /docs/ by relative links."""
    seen, todo = set(), ["index.html"]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        code, h, body = get(base + "/docs/" + name)
        if code != 200:
            fail("/docs/%s: %d" % (name, code))
        again = get(base + "/docs/" + name,
                    headers={"If-None-Match": h.get("ETag", "none")})
        if again[0] != 304:
            fail("/docs/%s with its ETag: %d, not 304" % (name, again[0]))
        if not h.get("Content-Type", "").startswith("text/html"):
            continue
        refs = Refs()
        refs.feed(body.decode("utf-8"))
        for ref in refs.refs:
            u = urllib.parse.urlsplit(ref)
            if u.scheme or u.netloc or not u.path or ref.startswith("/"):
                continue
            todo.append(posixpath.normpath(posixpath.join(
                posixpath.dirname(name), u.path)))
    return seen


def main():
    if len(sys.argv) != 3 or sys.argv[2] not in ("built", "none"):
        sys.exit(__doc__)
    proc, base = start(sys.argv[1])
    try:
        if sys.argv[2] == "none":
            problem(base, "/docs/", 404, says="built without")
            print("check_docs: a build without the guide says so")
            return
        code, h, body = get(base + "/docs/")
        if code != 200 or not h["Content-Type"].startswith("text/html") or \
                b"<title>stickslip</title>" not in body:
            fail("/docs/: %d %s" % (code, h.get("Content-Type")))
        files = crawl(base)
        kinds = {posixpath.splitext(f)[1] for f in files}
        for want in (".html", ".css", ".js", ".png"):
            if want not in kinds:
                fail("no %s file reached from /docs/" % want)
        problem(base, "/docs/no-such-page.html", 404, says="no such page")
        problem(base, "/docs", 404, says="/docs/")
        problem(base, "/docs/", 405, method="POST")
        print("check_docs: %d files of the guide served, each with its "
              "validator" % len(files))
    finally:
        proc.terminate()
        proc.wait()


if __name__ == "__main__":
    main()
