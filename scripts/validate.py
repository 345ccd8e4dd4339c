#!/usr/bin/env python3
"""Every answer of a live daemon against the contract's schemas.

  python3 scripts/validate.py PATH/stickslipd

Starts the daemon on a free port and sends it every request the repository
holds: each request example of api/openapi.json, each codec case of
tests/api/cases (success and problem alike, to the endpoint its name
starts with), and a GET of each GET endpoint (of each value a path
parameter lists: every problem type's page), plus an unknown path and a
wrong method.  Each answer's status must be one the contract lists for that
path (or a problem status of its "default"), its Content-Type the one listed
there, and its JSON body valid under the listed schema (JSON Schema 2020-12,
as OpenAPI 3.1 and 3.2 use, with the document's $refs), by the python3-jsonschema
validator; every answer must carry X-Request-Id (a 405 Allow, a 503
Retry-After).  NDJSON answers are checked line by line, each line under the
itemSchema of the media type (OpenAPI 3.2); an endpoint that answers in
JSON and NDJSON is asked each example in both (Accept).  Two requests with smuggling framing check
the 400 every path may give.  Exit 0 when
every answer is valid; 77 when jsonschema is not installed.
"""
import email.message
import glob
import json
import os
import re
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

try:
    import jsonschema
except ImportError:
    print("validate: python3-jsonschema is not installed, skipped")
    sys.exit(77)

# two Content-Length headers: refused with 400 and a closed connection
RAW = ("%s %s HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
       "Content-Length: 2\r\nContent-Length: 40\r\n\r\n{}")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def start(binary, state):
    p = subprocess.Popen([binary, "--port", "0", "--quiet", "--state-dir",
                          state],
                         stderr=subprocess.PIPE, text=True)
    m = re.search(r"http://[^ \n]+", p.stderr.readline())
    if not m:
        p.kill()
        sys.exit("validate: the daemon did not start")
    return p, m.group(0).rstrip("/")


def send(base, method, path, body=None, accept=None, prefer=None):
    data = body.encode() if body is not None else None
    headers = {"Content-Type": "application/json"} if body is not None else {}
    if accept:
        headers["Accept"] = accept
    if prefer:
        headers["Prefer"] = prefer
    req = urllib.request.Request(base + path, data=data, method=method,
                                 headers=headers)
    try:
        with urllib.request.urlopen(req, timeout=120) as r:
            return r.status, r.headers, r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, e.headers, e.read().decode()


def send_raw(base, head):
    """A request written byte for byte (framing urllib will not send):
    the status, the headers and the body of the answer."""
    host, port = base.split("//")[1].rsplit(":", 1)
    with socket.create_connection((host.strip("[]"), int(port)), 30) as s:
        s.sendall(head.encode())
        data = b""
        while True:
            got = s.recv(65536)
            if not got:
                break
            data += got
    head_text, _, body = data.partition(b"\r\n\r\n")
    lines = head_text.decode("latin-1").split("\r\n")
    status = int(lines[0].split()[1])
    headers = email.message.Message()
    for line in lines[1:]:
        k, _, v = line.partition(":")
        headers[k.strip()] = v.strip()
    return status, headers, body.decode()


def resolve(spec, obj):
    """@a obj, or what its local $ref names."""
    ref = obj.get("$ref", "")
    if not ref.startswith("#/"):
        return obj
    for part in ref[2:].split("/"):
        spec = spec[part]
    return spec


def op_of(spec, template, method, path):
    """The contract's operation for @a method on @a path (a concrete path
    made from a template, or with a query), or None."""
    path = path.split("?")[0]
    return spec["paths"].get(template.get(path, path), {}).get(method.lower())


def check(spec, op, method, path, status, headers, text, bad):
    """The answer against the contract's operation @a op (None: an unknown
    path or method); its faults appended to @a bad.  The number of answers
    (NDJSON lines) found valid."""
    ctype = headers.get("Content-Type", "")
    where = "%s %s -> %d" % (method, path, status)
    # the headers every answer, or every such answer, carries
    if not headers.get("X-Request-Id"):
        bad.append(where + ": no X-Request-Id")
    if status == 503 and not headers.get("Retry-After"):
        bad.append(where + ": a 503 without Retry-After")
    if status == 405 and not headers.get("Allow"):
        bad.append(where + ": a 405 without Allow")
    if op is None:  # an unknown path or method: a problem
        ok = status in (404, 405) and \
            ctype.startswith("application/problem+json")
        schema = spec["components"]["schemas"]["Problem"]
        if not ok:
            bad.append(where + ": expected a 404/405 problem")
            return 0
    else:
        resp = op["responses"].get(str(status))
        if resp is None:
            bad.append(where + ": status not in the contract")
            return 0
        resp = resolve(spec, resp)
        media = ctype.split(";")[0].strip()
        content = resp.get("content", {})
        if media not in content:
            bad.append(where + ": %s not in the contract (%s)" %
                       (media, ", ".join(content)))
            return 0
        # an NDJSON answer: each line under the item schema
        schema = content[media].get("itemSchema",
                                    content[media].get("schema", {}))
    if "json" not in ctype:
        return 1  # text (the metrics): its media type is checked
    lines = [text] if "ndjson" not in ctype else \
        [line for line in text.splitlines() if line.strip()]
    valid = 0
    for line in lines:
        try:
            value = json.loads(line)
            full = dict(schema)
            full["components"] = spec["components"]
            jsonschema.validate(value, full,
                                cls=jsonschema.Draft202012Validator)
            valid += 1
        except (ValueError, jsonschema.ValidationError) as e:
            msg = getattr(e, "message", str(e))
            path_in = "/".join(str(p) for p in getattr(e, "absolute_path", []))
            bad.append("%s: at /%s: %s" % (where, path_in, msg[:200]))
    return valid


def check_job(spec, base, bad):
    """A job's documents under the contract: created (201), read once it
    is done, listed, its results, dismissed, and read again (dismissed)."""
    body = json.dumps({"params": {"chi": 0.2, "eta": 4, "us": 0.0724,
                                  "ur": 0.6178, "V": 1},
                       "initial": [0.1, 0, 0, 0], "t_end": 10})
    template, valid = {}, 0
    status, headers, text = send(base, "POST", "/simulate", body,
                                 prefer="respond-async")
    valid += check(spec, op_of(spec, template, "POST", "/simulate"), "POST",
                   "/simulate (async)", status, headers, text, bad)
    loc = headers.get("Location", "")
    if status != 201 or not loc.startswith("/jobs/"):
        bad.append("POST /simulate (async) -> %d: no job (Location %r)" %
                   (status, loc))
        return valid
    template[loc] = "/jobs/{jobId}"
    template[loc + "/results"] = "/jobs/{jobId}/results"
    for _ in range(300):  # its status, read until it is done (30 s at most)
        status, headers, text = send(base, "GET", loc)
        if status != 200 or json.loads(text).get("status") not in (
                "accepted", "running"):
            break
        time.sleep(0.1)
    valid += check(spec, op_of(spec, template, "GET", loc), "GET", loc,
                   status, headers, text, bad)
    for method, path in (("GET", "/jobs"), ("GET", loc + "/results"),
                         ("DELETE", loc), ("GET", loc)):
        status, headers, text = send(base, method, path)
        valid += check(spec, op_of(spec, template, method, path), method,
                       path, status, headers, text, bad)
    after = json.loads(text) if status == 200 else {}
    if after.get("status") != "dismissed" or after.get("progress") != 100:
        # the job had succeeded: its progress does not go back
        bad.append("GET %s after DELETE -> %d, not dismissed at 100: %.200s"
                   % (loc, status, text))
    return valid


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    spec = json.load(open(os.path.join(ROOT, "api", "openapi.json")))
    # the document as the root of its own $refs
    registry_root = spec
    paths = spec["paths"]
    requests = []  # (method, path, body)
    template = {}  # a path made from a template: the template
    for path, item in paths.items():
        for method, op in item.items():
            if method == "get":
                requests.append(("GET", path, None))
                # a path parameter that lists its values: each value
                for par in item.get("parameters", []):
                    par = resolve(spec, par)
                    for v in par.get("schema", {}).get("enum", []):
                        concrete = path.replace("{%s}" % par["name"], v)
                        template[concrete] = path
                        requests.append(("GET", concrete, None))
            if method == "post":
                exs = (op.get("requestBody", {}).get("content", {})
                       .get("application/json", {}).get("examples", {}))
                ok = op.get("responses", {}).get("200", {}).get("content", {})
                for ex in exs.values():
                    requests.append(("POST", path, json.dumps(ex["value"])))
                    # an endpoint's other form, asked for with Accept
                    if "application/json" in ok and \
                            "application/x-ndjson" in ok:
                        requests.append(("POST", path, json.dumps(ex["value"]),
                                         "application/x-ndjson"))
    labels = {p.strip("/").replace(".json", ""): p for p in paths}
    for case in sorted(glob.glob(os.path.join(ROOT, "tests", "api", "cases",
                                              "*", "request.json"))):
        name = os.path.basename(os.path.dirname(case))
        if os.path.exists(os.path.join(os.path.dirname(case), "limits.json")):
            continue  # a case for other limits than the daemon's defaults
        label = name.split("-")[0]
        if label in labels:
            requests.append(("POST", labels[label], open(case).read()))
    requests += [("GET", "/nowhere", None), ("GET", "/orbit", None),
                 ("POST", "/health", "{}")]
    # framing that could smuggle a request, on a cheap and a computing path
    for method, path in (("GET", "/health"), ("POST", "/orbit")):
        requests.append((method, path, RAW % (method, path)))
    state = tempfile.TemporaryDirectory()
    proc, base = start(sys.argv[1], state.name)
    bad, checked = [], 0
    try:
        for method, path, body, *accept in requests:
            if body is not None and body.startswith(method + " "):
                status, headers, text = send_raw(base, body)
            else:
                status, headers, text = send(base, method, path, body,
                                             *accept)
            checked += check(spec, op_of(spec, template, method, path),
                             method, path, status, headers, text, bad)
        checked += check_job(spec, base, bad)
    finally:
        proc.terminate()
        proc.wait()
        state.cleanup()
    for b in bad[:40]:
        print(b)
    print("validate: %d requests, %d answers valid, %d not" %
          (len(requests), checked, len(bad)))
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
