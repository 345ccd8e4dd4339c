#!/usr/bin/env python3
"""Run one notebook top to bottom against a daemon of its own:

  python3 notebooks/run.py STICKSLIPD NOTEBOOK [FIGURES_DIR]

Starts STICKSLIPD on a free port, with a job store of its own in a
temporary directory, then `jupyter nbconvert --execute` (from
Debian's jupyter-nbconvert) with STICKSLIP_URL set to it and the figures
written to FIGURES_DIR (default: notebooks/figures, the committed ones);
the executed notebook goes beside the figures.  Fails when a cell fails or
writes a warning, or when a figure the notebook names was not written;
exits 77 (skipped) when nbconvert or the kernel's packages are missing.
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def main() -> int:
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    binary, notebook = sys.argv[1], os.path.abspath(sys.argv[2])
    figures = os.path.abspath(sys.argv[3] if len(sys.argv) > 3
                              else os.path.join(HERE, "figures"))
    nbconvert = shutil.which("jupyter-nbconvert")
    probe = subprocess.run([sys.executable, "-c",
                            "import ipykernel, matplotlib, numpy, pandas"],
                           capture_output=True)
    if not nbconvert or probe.returncode:
        print("notebooks: jupyter-nbconvert, python3-ipykernel, "
              "-matplotlib, -numpy or -pandas missing: skipped")
        return 77
    state = tempfile.mkdtemp(prefix="stickslip-notebook-")
    d = subprocess.Popen([binary, "--port", "0", "--quiet",
                          "--max-seconds", "120", "--state-dir", state,
                          "--job-store",
                          "sqlite:" + os.path.join(state, "jobs.sqlite")],
                         stderr=subprocess.PIPE, text=True)
    line = d.stderr.readline() if d.stderr else ""
    m = re.search(r"http://[^ \n]+", line)
    if not m:
        d.kill()
        sys.exit("notebooks: the daemon did not start: " + line)
    os.makedirs(figures, exist_ok=True)
    env = dict(os.environ, STICKSLIP_URL=m.group(0).rstrip("/"),
               PYDEVD_DISABLE_FILE_VALIDATION="1",
               STICKSLIP_FIGURES=figures)
    start = time.time()
    try:
        rc = subprocess.run([nbconvert, "--execute", "--to", "notebook",
                             "--ExecutePreprocessor.timeout=120",
                             "--output-dir", figures, notebook],
                            env=env, cwd=HERE).returncode
    finally:
        d.terminate()
        d.wait()
        shutil.rmtree(state, ignore_errors=True)
    executed = os.path.join(figures, os.path.basename(notebook))
    return rc or warnings(executed) or unwritten(executed, figures, start)


def warnings(executed: str) -> int:
    """1 when a cell of the executed notebook wrote a warning (a reader
    would see it under the cell), after printing it."""
    with open(executed) as f:
        cells = json.load(f)["cells"]
    said = ["".join(out.get("text", "")) for cell in cells
            for out in cell.get("outputs", [])
            if out.get("name") == "stderr"]
    said = [text for text in said if "Warning" in text]
    for text in said:
        print("notebooks: a cell warned:\n" + text)
    return 1 if said else 0


def unwritten(executed: str, figures: str, since: float) -> int:
    """1 when a figure the notebook's cells name ("name.png") was not
    written to ``figures`` by this run, after saying which."""
    with open(executed) as f:
        cells = json.load(f)["cells"]
    names = sorted({name for cell in cells if cell["cell_type"] == "code"
                    for name in re.findall(r'"([\w-]+\.png)"',
                                           "".join(cell["source"]))})
    stale = [n for n in names
             if not os.path.exists(os.path.join(figures, n))
             or os.path.getmtime(os.path.join(figures, n)) < since - 1]
    for n in stale:
        print("notebooks: %s was not written" % n)
    print("notebooks: %d figures written to %s" % (len(names) - len(stale),
                                                   figures))
    return 1 if stale or not names else 0


if __name__ == "__main__":
    sys.exit(main())
