#!/usr/bin/env python3
"""The user's guide (docs/) built to HTML, checked, and embedded in stickslipd.

  python3 scripts/docs.py build OUT         build OUT/site with mkdocs --strict
  python3 scripts/docs.py links SITE        check every relative link and anchor
  python3 scripts/docs.py embed SITE FILE.c the site as a C table for the daemon

build copies docs/ to OUT/src with the pages made from other files of the
tree: reference/http.md from the contract (api/openapi.json),
reference/c-api.md from the public header's comments
(core/include/stickslip.h) and changelog.md (CHANGELOG.md); then runs
mkdocs (Debian's package, see scripts/setup.sh) with warnings as errors, and
checks the links of what it built.  Exit 77 when mkdocs is missing (a test
skipped).  Standard library only, besides mkdocs itself.
"""
import hashlib
import html.parser
import json
import os
import posixpath
import re
import shutil
import subprocess
import sys
import urllib.parse

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# ---- the HTTP reference, from the contract ---------------------------------


def schema_type(s):
    """A schema's type as a reader says it: number, array of Orbit, ..."""
    if "$ref" in s:
        name = s["$ref"].rsplit("/", 1)[1]
        return "[%s](#schema-%s)" % (name, name.lower())
    for key in ("oneOf", "anyOf"):
        if key in s:
            return " or ".join(schema_type(x) for x in s[key])
    t = s.get("type", "any")
    if isinstance(t, list):
        t = " or ".join(t)
    if t == "array" and "items" in s:
        return "array of " + schema_type(s["items"])
    if "enum" in s:
        return t + ": " + ", ".join("`%s`" % json.dumps(v) for v in s["enum"])
    return t


def bounds(s):
    out = []
    for key, sign in (("minimum", ">="), ("exclusiveMinimum", ">"),
                      ("maximum", "<="), ("exclusiveMaximum", "<")):
        if key in s:
            out.append("%s %s" % (sign, s[key]))
    if "default" in s:
        out.append("default `%s`" % json.dumps(s["default"]))
    return "; ".join(out)


def cell(text):
    return " ".join(str(text).split()).replace("|", "\\|")


def http_reference(spec):
    doc = json.load(open(spec))
    out = ["# HTTP reference", "",
           "Made from the contract, `api/openapi.json` (OpenAPI %s), version "
           "%s, when the guide is built; the daemon serves the same document "
           "at `GET /openapi.json`. The pages of the HTTP API section say "
           "what each endpoint is for, with examples." %
           (doc["openapi"], doc["info"]["version"]), ""]
    out += ["## Endpoints", "", "| method | path | what |", "| --- | --- | --- |"]
    ops = []
    for path, item in doc["paths"].items():
        for method, op in item.items():
            if isinstance(op, dict) and "responses" in op:
                ops.append((path, method, op))
                out.append("| %s | [`%s`](#%s) | %s |" % (
                    method.upper(), path, op["operationId"].lower(),
                    cell(op.get("summary", ""))))
    out.append("")
    for path, method, op in ops:
        out += ['## %s %s {#%s}' % (method.upper(), path,
                                   op["operationId"].lower()), ""]
        if op.get("description"):
            out += [op["description"].strip(), ""]
        params = [doc["components"]["parameters"][
            p["$ref"].rsplit("/", 1)[1]] if "$ref" in p else p
            for p in op.get("parameters", [])]
        if params:
            out += ["| parameter | in | type | what |", "| --- | --- | --- | --- |"]
            for p in params:
                out.append("| `%s` | %s | %s | %s |" % (
                    p["name"], p["in"], schema_type(p.get("schema", {})),
                    cell(p.get("description", ""))))
            out.append("")
        body = op.get("requestBody", {}).get("content", {})
        for media, m in body.items():
            sch = m.get("schema", {})
            sch = sch["allOf"][0] if len(sch.get("allOf", [])) == 1 else sch
            out += ["Request: `%s`, %s." % (media, schema_type(sch)), ""]
        out += ["| status | media type | body |", "| --- | --- | --- |"]
        for code, r in op["responses"].items():
            if "$ref" in r:
                r = doc["components"]["responses"][r["$ref"].rsplit("/", 1)[1]]
            content = r.get("content") or {"": {}}
            for media, m in content.items():
                sch = m.get("schema") or m.get("itemSchema") or {}
                what = schema_type(sch) if sch else cell(r.get("description", ""))
                if "itemSchema" in m and sch:
                    what = "lines, each " + what
                out.append("| %s | %s | %s |" % (code, media and "`%s`" % media,
                                                 what))
        out.append("")
    out += ["## Schemas", ""]
    for name, s in doc["components"]["schemas"].items():
        # schema-: an operation and a schema may share a name (stability)
        out += ["### %s {#schema-%s}" % (name, name.lower()), ""]
        if s.get("description"):
            out += [cell(s["description"]), ""]
        props = s.get("properties")
        if not props:
            out += ["%s." % schema_type(s), ""]
            continue
        req = set(s.get("required", []))
        out += ["| field | type | required | what |", "| --- | --- | --- | --- |"]
        for k, p in props.items():
            what = cell(p.get("description", ""))
            extra = bounds(p)
            out.append("| `%s` | %s | %s | %s |" % (
                k, schema_type(p), "yes" if k in req else "",
                "; ".join(x for x in (what, extra) if x)))
        out.append("")
    anchors = re.findall(r"\{#([^}]+)\}", "\n".join(out))
    twice = sorted({a for a in anchors if anchors.count(a) > 1})
    if twice:
        raise SystemExit("docs: the HTTP reference has anchors twice: %s" %
                         ", ".join(twice))
    return "\n".join(out)

# ---- the C reference, from the header's comments ---------------------------


def c_name(decl):
    """The name a declaration declares: a function's, a macro's, a type's."""
    m = re.match(r"#define (\w+)", decl)
    if m:
        return m.group(1)
    m = re.search(r"}\s*(\w+);\s*$", decl)
    if m:
        return m.group(1)
    m = re.search(r"(\w+)\s*\(", decl)
    if m and not decl.startswith("typedef"):
        return m.group(1)
    m = re.search(r"(\w+)\s*[;\[]", decl)
    return m.group(1) if m else decl.split()[0]


def c_reference(header):
    """The header's opening comment, then each of its sections (a banner
    comment) with every declaration that has a Doxygen comment: the
    declaration as written, then its comment, in the header's order."""
    lines = open(header).read().split("\n")
    out = ["# C reference", "",
           "Made from `core/include/stickslip.h` when the guide is built: "
           "each declaration of the header with the comment above it, in the "
           "header's order.", ""]
    i, n = 0, len(lines)
    while i < n and not lines[i].startswith(" */"):
        i += 1
    out += ["```text"] + [re.sub(r"^ ?\* ?|^/\*", "", l).rstrip()
                          for l in lines[:i]] + ["```", ""]
    while i < n:
        line = lines[i]
        banner = re.match(r"^/\* (\w[^*]*?)\s*\*/$", line)
        if banner and i and lines[i - 1].startswith("/* ---"):
            out += ["## %s" % banner.group(1), ""]
        if not line.startswith("/**"):
            i += 1
            continue
        comment = []
        while True:
            comment.append(lines[i])
            if "*/" in lines[i]:
                break
            i += 1
        i += 1
        decl, depth = [], 0
        while i < n:
            decl.append(lines[i])
            depth += lines[i].count("{") - lines[i].count("}")
            if decl[0].startswith("#"):
                if not lines[i].endswith("\\"):
                    break
            elif depth == 0 and lines[i].rstrip().endswith(";"):
                break
            i += 1
        i += 1
        text = "\n".join(decl).strip()
        body = [re.sub(r"^\s*/?\*+/? ?", "", l).replace("*/", "").rstrip()
                for l in comment]
        out += ["### %s" % c_name(text), "", "```c", text, "```", ""]
        out += [l for l in body if l or out[-1]] + [""]
    return "\n".join(out)

# ---- the build ---------------------------------------------------------------


def build(out):
    mkdocs = shutil.which("mkdocs")
    if not mkdocs:
        print("docs: no mkdocs (apt-get install mkdocs; scripts/setup.sh)")
        return 77
    src = os.path.join(out, "src")
    shutil.rmtree(src, ignore_errors=True)
    shutil.copytree(os.path.join(ROOT, "docs"), src)
    os.makedirs(os.path.join(src, "reference"), exist_ok=True)
    gen = {
        "reference/http.md": http_reference(
            os.path.join(ROOT, "api", "openapi.json")),
        "reference/c-api.md": c_reference(
            os.path.join(ROOT, "core", "include", "stickslip.h")),
        "changelog.md": open(os.path.join(ROOT, "CHANGELOG.md")).read(),
    }
    for name, text in gen.items():
        with open(os.path.join(src, name), "w") as f:
            f.write(text)
    conf = open(os.path.join(ROOT, "mkdocs.yml")).read()
    conf = re.sub(r"(?m)^docs_dir:.*$", "docs_dir: src", conf)
    conf = re.sub(r"(?m)^site_dir:.*$", "site_dir: site", conf)
    with open(os.path.join(out, "mkdocs.yml"), "w") as f:
        f.write(conf)
    r = subprocess.run([mkdocs, "build", "--strict", "--clean",
                        "-f", os.path.join(out, "mkdocs.yml")])
    if r.returncode:
        print("docs: mkdocs build --strict failed")
        return 1
    return links(os.path.join(out, "site"))

# ---- links -------------------------------------------------------------------


class Page(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.ids, self.refs = set(), []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if a.get("id"):
            self.ids.add(a["id"])
        if tag == "a" and a.get("name"):
            self.ids.add(a["name"])
        for k in ("href", "src"):
            if a.get(k):
                self.refs.append((a[k], self.getpos()[0]))


def links(site):
    """Every relative href and src of the built pages names a file of the
    site, and every #anchor an id of its page."""
    pages = {}
    for d, _, files in os.walk(site):
        for f in files:
            if f.endswith(".html"):
                p = Page()
                p.feed(open(os.path.join(d, f), encoding="utf-8").read())
                pages[os.path.relpath(os.path.join(d, f), site)] = p
    bad = 0
    for name, p in sorted(pages.items()):
        for ref, line in p.refs:
            u = urllib.parse.urlsplit(ref)
            if u.scheme or u.netloc or ref.startswith("/"):
                continue
            target = posixpath.normpath(posixpath.join(
                posixpath.dirname(name), urllib.parse.unquote(u.path))) \
                if u.path else name
            if u.path.endswith("/") or os.path.isdir(os.path.join(site,
                                                                  target)):
                target = posixpath.join(target, "index.html")
            if not os.path.exists(os.path.join(site, target)):
                print("%s:%d: %s: no such file" % (name, line, ref))
                bad += 1
            elif u.fragment and target in pages and \
                    u.fragment not in pages[target].ids:
                print("%s:%d: %s: no such anchor" % (name, line, ref))
                bad += 1
    print("docs: %d pages, %s" % (len(pages), "%d bad links" % bad if bad
                                  else "every link resolves"))
    return 1 if bad else 0

# ---- the table the daemon serves ---------------------------------------------


TYPES = {".html": "text/html; charset=utf-8", ".css": "text/css; charset=utf-8",
         ".js": "text/javascript; charset=utf-8", ".png": "image/png",
         ".ico": "image/x-icon", ".woff": "font/woff", ".woff2": "font/woff2",
         ".svg": "image/svg+xml", ".xml": "application/xml",
         ".json": "application/json", ".txt": "text/plain; charset=utf-8"}
# The fonts' older formats: every browser the explorer runs in takes woff2.
SKIP = re.compile(r"(^fonts/.*\.(eot|ttf|otf|svg)$)|\.gz$")


def embed(site, cfile):
    rows, arrays = [], []
    names = sorted(os.path.relpath(os.path.join(d, f), site)
                   for d, _, fs in os.walk(site) for f in fs)
    for i, name in enumerate(n for n in names if not SKIP.search(n)):
        ext = os.path.splitext(name)[1]
        if ext not in TYPES:
            sys.exit("docs: no media type for " + name)
        data = open(os.path.join(site, name), "rb").read()
        hexes = ",".join("0x%02x" % b for b in data)
        arrays.append("static const char f%d[] = {%s,0x00};" % (i, hexes))
        etag = hashlib.sha1(data).hexdigest()[:16]
        rows.append('  {"%s", "%s", "\\"%s\\"", f%d, %d},' % (
            name, TYPES[ext], etag, i, len(data)))
    with open(cfile + ".tmp", "w") as f:
        f.write("/* Generated by scripts/docs.py from the built guide: do not "
                "edit. */\n#include \"docs.h\"\n\n/* clang-format off */\n")
        f.write("\n".join(arrays))
        f.write("\nconst api__doc_file api__docs[] = {\n%s\n  {0, 0, 0, 0, 0}};"
                "\nconst size_t api__n_docs = %d;\n/* clang-format on */\n" %
                ("\n".join(rows), len(rows)))
    os.replace(cfile + ".tmp", cfile)
    return 0


def main():
    a = sys.argv[1:]
    if len(a) == 2 and a[0] == "build":
        sys.exit(build(a[1]))
    if len(a) == 2 and a[0] == "links":
        sys.exit(links(a[1]))
    if len(a) == 3 and a[0] == "embed":
        sys.exit(embed(a[1], a[2]))
    sys.exit(__doc__)


if __name__ == "__main__":
    main()
