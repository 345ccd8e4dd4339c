#!/usr/bin/env python3
"""The layers' dependencies as the object files record them.

DESIGN.md section 2: dependencies point one way, server -> api -> core.  A
header can be included without being used, and a function can be declared
in a file that does not include its header; the object files cannot lie:
each lists the symbols it defines and those it takes from elsewhere.  From
them this check builds the graph "file a calls a function or reads data of
file b" and fails when

  - a lower layer takes a symbol from a higher one (core from api or the
    server, api from the server);
  - the files of one layer that is checked for circles (core/src, api/src)
    depend on each other in a circle, however long.

One kind of edge is not a dependency of design but a dispatch: the endpoint
table (api/src/endpoints.c) holds every endpoint's functions, and /batch and
the metrics read the table.  --dispatch FROM=PREFIX leaves out the edges from
the object FROM to the objects whose names start with PREFIX.

usage: check_layers.py --nm NM [--dispatch FROM=PREFIX]...
         --layer NAME [--acyclic] OBJECT... [--layer NAME ...]
Layers are given lowest first.  An OBJECT argument may hold several paths
separated by ';' (a CMake list).  Exit 0 when every rule holds, 1 otherwise.
"""
import os
import subprocess
import sys


def parse_args(argv):
    nm, dispatch, layers = "nm", [], []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a == "--nm":
            nm = argv[i + 1]
            i += 2
            continue
        if a == "--dispatch":
            src, prefix = argv[i + 1].split("=", 1)
            dispatch.append((src, prefix))
            i += 2
            continue
        if a == "--layer":
            layers.append({"name": argv[i + 1], "acyclic": False, "objs": []})
            i += 2
            continue
        if a == "--acyclic":
            layers[-1]["acyclic"] = True
        else:
            layers[-1]["objs"] += [p for p in a.split(";") if p]
        i += 1
    return nm, dispatch, layers


def short(path):
    """decode.c.o -> decode.c; decode.o -> decode.c"""
    b = os.path.basename(path)
    if b.endswith(".o"):
        b = b[:-2]
    return b if b.endswith(".c") else b + ".c"


def symbols(nm, path):
    """The global symbols an object defines, and those it takes."""
    out = subprocess.run([nm, "-P", path], check=True, capture_output=True,
                         text=True).stdout
    defined, undefined = set(), set()
    for line in out.splitlines():
        f = line.split()
        if len(f) < 2:
            continue
        name, kind = f[0], f[1]
        if kind == "U":
            undefined.add(name)
        elif kind.isupper() and kind not in "UN":  # global, defined here
            defined.add(name)
    return defined, undefined


def circles(nodes, edges):
    """The strongly connected components of more than one node (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return found


def main(argv):
    nm, dispatch, layers = parse_args(argv)
    owner = {}  # symbol -> (layer index, object)
    objs = []   # (layer index, object, undefined symbols)
    for li, layer in enumerate(layers):
        if not layer["objs"]:
            print("layer %s has no objects" % layer["name"])
            return 1
        for path in layer["objs"]:
            d, u = symbols(nm, path)
            for s in d:
                owner[s] = (li, short(path))
            objs.append((li, short(path), u))
    bad = 0
    edges = {}  # (layer, object) -> {object: symbols}
    for li, obj, undefined in objs:
        for s in sorted(undefined):
            if s not in owner:
                continue  # libc, GSL, jansson, the sanitizers' runtime
            lj, other = owner[s]
            if lj > li:
                print("%s %s takes %s from %s %s: a lower layer may not "
                      "depend on a higher one" % (layers[li]["name"], obj, s,
                                                  layers[lj]["name"], other))
                bad = 1
            if lj != li or other == obj:
                continue
            if any(obj == src and other.startswith(p) for src, p in dispatch):
                continue
            edges.setdefault((li, obj), {}).setdefault(other, set()).add(s)
    for li, layer in enumerate(layers):
        names = sorted({o for lj, o, _ in objs if lj == li})
        graph = {o: set(edges.get((li, o), {})) for o in names}
        print("%s:" % layer["name"])
        for o in names:
            print("  %s -> %s" % (o, " ".join(sorted(graph[o])) or "-"))
        if not layer["acyclic"]:
            continue
        for comp in circles(names, graph):
            bad = 1
            print("%s: the files %s depend on each other in a circle:" %
                  (layer["name"], ", ".join(comp)))
            for o in comp:
                for other in sorted(graph[o] & set(comp)):
                    print("  %s -> %s (%s)" %
                          (o, other,
                           ", ".join(sorted(edges[(li, o)][other]))))
    return bad


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
