"""Without numpy and pandas (blocked in sys.modules of a fresh
interpreter) the package imports, the client and sweeps work, and the
arrays helpers say what to install; and the package installs offline."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import venv
from typing import Any, List

from conftest import HERE, Daemon

BLOCKED = """
import sys
sys.modules["numpy"] = None
sys.modules["pandas"] = None
sys.modules["tqdm"] = None
sys.path.insert(0, %r)
import stickslip, stickslip.arrays
c = stickslip.Client(%r)
P = {"chi": 0.2, "eta": 4, "us": 0.0724, "ur": 0.6178, "V": 1}
o = c.orbit(params=P, kind="overshoot", samples=5)["orbits"][0]
s = c.sweep([{"params": P, "kind": "overshoot"}], progress=True)
print(round(o["period"], 6), s[0]["status"])
try:
    stickslip.arrays.samples(o)
except ImportError as e:
    print(e)
assert "numpy" not in sys.modules or sys.modules["numpy"] is None
"""


def test_without_numpy_and_pandas(daemon: Daemon) -> None:
    out = subprocess.run([sys.executable, "-c",
                          BLOCKED % (os.path.dirname(HERE), daemon.url)],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "10.27143 200"
    assert lines[1].startswith("stickslip.arrays needs numpy")
    assert "sweep /orbit: 1/1 (100%)" in out.stderr


def test_pip_install_offline(tmp_path: Any) -> None:
    """``pip install ./python`` as a user runs it: in a venv of its own
    (no system packages), with pip's isolated build and no index; then
    the package, its py.typed and its command are there, and nothing else
    came with it."""
    src = str(tmp_path / "src")  # a copy: the source tree stays as it is
    shutil.copytree(os.path.dirname(HERE), src, ignore=shutil.ignore_patterns(
        "tests", "__pycache__", ".*cache"))
    env_dir = str(tmp_path / "venv")
    venv.create(env_dir, with_pip=True)
    py = os.path.join(env_dir, "bin", "python")
    before = pip_list(py)
    out = subprocess.run([py, "-m", "pip", "install", "--no-index", "-q",
                          src], capture_output=True, text=True, timeout=300,
                         cwd=str(tmp_path))
    assert out.returncode == 0, out.stderr
    assert pip_list(py) == sorted(before + ["stickslip"])
    out = subprocess.run([py, "-c", "import stickslip, os; "
                          "print(os.path.dirname(stickslip.__file__)); "
                          "print(os.path.exists(os.path.join("
                          "os.path.dirname(stickslip.__file__), 'py.typed')))"],
                         capture_output=True, text=True, cwd=str(tmp_path))
    where, typed = out.stdout.split()
    assert where.startswith(env_dir) and typed == "True"
    out = subprocess.run([os.path.join(env_dir, "bin", "stickslip"),
                          "--help"], capture_output=True, text=True)
    assert out.returncode == 0 and "orbit" in out.stdout


def pip_list(py: str) -> List[str]:
    out = subprocess.run([py, "-m", "pip", "list", "--format", "freeze"],
                         capture_output=True, text=True, check=True)
    return sorted(line.split("==")[0] for line in out.stdout.split())
