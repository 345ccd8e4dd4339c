#!/usr/bin/env python3
"""What a release says of itself, held to the tree.

  check_release.py version CMAKE_VERSION
      the one version (core/include/stickslip.h) is the one CMake read, and
      the one of the contract, the Python package, CITATION.cff and the
      changelog's latest release (whose date is CITATION.cff's too)
  check_release.py cff
      CITATION.cff against tests/release/cff.schema.json (python3-yaml,
      python3-jsonschema; exit 77 without them)
  check_release.py readme
      README.md is what a newcomer reads on a screen or two: under 200 lines
  check_release.py names STICKSLIPD
      every flag the README, the changelog and the guide name is a flag of
      `STICKSLIPD --help` (or one its option parser in server/main.c takes)
      or of the other tool that the table OTHER_TOOLS names, and every path
      of the repository they name exists

Exit 0 when it holds, 1 with what differs.
"""
import json
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))))


def read(*path):
    with open(os.path.join(ROOT, *path), encoding="utf-8") as f:
        return f.read()


def header_version():
    h = read("core", "include", "stickslip.h")
    parts = [re.search(r"#define SS_VERSION_%s (\d+)" % k, h).group(1)
             for k in ("MAJOR", "MINOR", "PATCH")]
    return ".".join(parts)


def one(pattern, text, what):
    m = re.search(pattern, text, re.M)
    return m.group(1) if m else "(no version found in %s)" % what


def version(cmake_version):
    v = header_version()
    release = re.search(r"^## \[(\d+\.\d+\.\d+)\] - (\d{4}-\d\d-\d\d)$",
                        read("CHANGELOG.md"), re.M)
    cff = read("CITATION.cff")
    found = {
        "CMake's project()": cmake_version,
        "api/openapi.json info.version":
            json.loads(read("api", "openapi.json"))["info"]["version"],
        "python/pyproject.toml": one(r'^version = "([^"]+)"',
                                     read("python", "pyproject.toml"),
                                     "pyproject.toml"),
        "python/stickslip/__init__.py": one(
            r'^__version__ = "([^"]+)"',
            read("python", "stickslip", "__init__.py"), "__init__.py"),
        "CITATION.cff version": one(r"^version: (\S+)", cff, "CITATION.cff"),
        "CHANGELOG.md's latest release":
            release.group(1) if release else "(no release section)",
    }
    bad = ["%s says %s" % (k, x) for k, x in found.items() if x != v]
    date = one(r'^date-released: "?([0-9-]+)"?', cff, "CITATION.cff")
    if release and date != release.group(2):
        bad.append("CITATION.cff date-released %s, CHANGELOG.md %s" %
                   (date, release.group(2)))
    for b in bad:
        print("version: core/include/stickslip.h says %s; %s" % (v, b))
    if not bad:
        print("version: %s everywhere (%s)" % (v, ", ".join(found)))
    return 1 if bad else 0


def cff():
    try:
        import jsonschema
        import yaml
    except ImportError as e:
        print("cff: %s (apt-get install python3-yaml python3-jsonschema)" % e)
        return 77
    doc = yaml.safe_load(read("CITATION.cff"))
    # YAML reads an unquoted date as a date; the format's dates are strings
    schema = json.loads(read("tests", "release", "cff.schema.json"))
    errors = sorted(jsonschema.Draft202012Validator(schema).iter_errors(doc),
                    key=lambda e: list(e.path))
    for e in errors:
        print("CITATION.cff: /%s: %s" % ("/".join(map(str, e.path)),
                                         e.message))
    if not errors:
        print("cff: CITATION.cff is valid")
    return 1 if errors else 0


# Flags of tools other than stickslipd that the pages name, by tool.
OTHER_TOOLS = {
    "mkdocs build": ["--strict"],
    "pkg-config": ["--cflags", "--libs", "--static", "--variable"],
    "systemctl": ["--now"],
    "cmake": ["--build", "--install", "--prefix", "--target"],
    "docker": ["--build-arg", "--rm", "--scale"],
    "scripts/setup.sh": ["--test"],
    "scripts/examples.py": ["--check", "--write"],
    "bench/jobs.py": ["--repeat"],
    "jupyter nbconvert": ["--execute"],
    "python -m stickslip": ["--chi"],
    "curl": ["--parallel-max"],
}
# Top-level entries of the tree: a word in backquotes that starts with one
# of these is a path of the repository.
TREE = ("core/", "api/", "server/", "tests/", "scripts/", "docs/", "python/",
        "notebooks/", "bench/", "docker/", "packaging/", ".ci/")
# Files the pages tell a user to make.
MADE_BY_USER = ("docker/postgres.env",)
FILES = ("README.md", "CHANGELOG.md", "CITATION.cff", "LICENSE", "mkdocs.yml",
         "CMakeLists.txt")


def pages():
    out = [os.path.join(ROOT, "README.md"), os.path.join(ROOT, "CHANGELOG.md")]
    for d, _, fs in os.walk(os.path.join(ROOT, "docs")):
        out += [os.path.join(d, f) for f in sorted(fs) if f.endswith(".md")]
    return out


def names(stickslipd):
    r = subprocess.run([stickslipd, "--help"], capture_output=True,
                       text=True)
    helptext = r.stdout + r.stderr
    daemon = set(re.findall(r"--[a-z][a-z0-9-]*", helptext)) | set(
        re.findall(r'"(--[a-z][a-z0-9-]*)', read("server", "main.c")))
    other = {f for fs in OTHER_TOOLS.values() for f in fs}
    bad, nflags, npaths = [], set(), set()
    for page in pages():
        text = open(page, encoding="utf-8").read()
        rel = os.path.relpath(page, ROOT)
        for n, line in enumerate(text.split("\n"), 1):
            for flag in re.findall(r"(?<![-\w])--[a-z][a-z0-9-]*", line):
                nflags.add(flag)
                if flag not in daemon and flag not in other:
                    bad.append("%s:%d: %s is no flag of stickslipd --help" %
                               (rel, n, flag))
            words = re.findall(r"`([^`\s]+)`", line)
            if not rel.startswith("docs"):
                # (links between the guide's pages: mkdocs --strict)
                words += re.findall(r"\]\(([^)#\s]+)", line)
            for word in words:
                word = word.rstrip(".,:;")
                if word.startswith(TREE) or word in FILES:
                    path = word
                else:
                    continue
                if re.search(r"[<>*{}$]|\.\.\.", path) or path in MADE_BY_USER:
                    continue  # a pattern, not a path
                npaths.add(path)
                if not os.path.exists(os.path.join(ROOT, path)):
                    bad.append("%s:%d: %s does not exist" % (rel, n, path))
    for b in bad:
        print(b)
    print("names: %d flags and %d paths named in README.md, CHANGELOG.md and "
          "docs/: %s" % (len(nflags), len(npaths),
                         "%d wrong" % len(bad) if bad else "all exist"))
    return 1 if bad else 0


def readme():
    n = read("README.md").count("\n")
    print("readme: README.md has %d lines (at most 199)" % n)
    return 0 if n < 200 else 1


def main():
    a = sys.argv[1:]
    if len(a) == 2 and a[0] == "version":
        sys.exit(version(a[1]))
    if a == ["cff"]:
        sys.exit(cff())
    if a == ["readme"]:
        sys.exit(readme())
    if len(a) == 2 and a[0] == "names":
        sys.exit(names(a[1]))
    sys.exit(__doc__)


if __name__ == "__main__":
    main()
