"""The README's "From Python" example runs against the daemon and prints
the output the README shows under it."""

from __future__ import annotations

import os
import re
import subprocess
import sys

from conftest import HERE, Daemon

README = os.path.join(os.path.dirname(os.path.dirname(HERE)), "README.md")


def test_readme_example(daemon: Daemon) -> None:
    text = open(README).read()
    section = text.split("### From Python\n", 1)[1]
    m = re.search(r"```python\n(.*?)```\n```text\n(.*?)```\n", section, re.S)
    assert m, "no python block and output under From Python"
    code, want = m.group(1), m.group(2)
    assert len(code.strip().splitlines()) <= 10
    env = dict(os.environ, PYTHONPATH=os.path.dirname(HERE),
               STICKSLIP_URL=daemon.url)
    out = subprocess.run([sys.executable, "-c", code], env=env,
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout == want
