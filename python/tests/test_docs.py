"""Every Python example of the README and the user's guide (docs/) runs
against the daemon, and prints the output shown under it (a ```text block
right after the ```python block), where one is shown."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from typing import Iterator, List, Optional, Tuple

import pytest

from conftest import HERE, Daemon

ROOT = os.path.dirname(os.path.dirname(HERE))
BLOCK = re.compile(r"^```python\n(.*?)^```\n(?:```text\n(.*?)^```\n)?",
                   re.S | re.M)


def examples() -> List[Tuple[str, int, str, Optional[str]]]:
    pages = [os.path.join(ROOT, "README.md")] + sorted(
        os.path.join(d, f) for d, _, fs in os.walk(os.path.join(ROOT, "docs"))
        for f in fs if f.endswith(".md"))
    out = []
    for page in pages:
        text = open(page).read()
        for m in BLOCK.finditer(text):
            line = text[:m.start()].count("\n") + 1
            out.append((os.path.relpath(page, ROOT), line, m.group(1),
                        m.group(2)))
    return out


EXAMPLES = examples()


def test_readme_has_one() -> None:
    # the README's one Python call, short enough to read at a glance, with
    # its output shown (and so checked by test_example)
    mine = [e for e in EXAMPLES if e[0] == "README.md"]
    assert len(mine) == 1
    assert len(mine[0][2].strip().splitlines()) <= 10
    assert mine[0][3]


@pytest.fixture(scope="module")
def lenient(binary: str) -> Iterator[Daemon]:
    """A daemon whose time limit leaves room for the examples under the
    sanitizers on a loaded machine (ten to twenty times slower than the
    daemon they were written with); the answers do not depend on it."""
    d = Daemon(binary, ["--max-seconds", "120"])
    yield d
    d.stop()


@pytest.mark.parametrize("page,line,code,want", EXAMPLES,
                         ids=["%s:%d" % (e[0], e[1]) for e in EXAMPLES])
def test_example(lenient: Daemon, page: str, line: int, code: str,
                 want: Optional[str]) -> None:
    env = dict(os.environ, PYTHONPATH=os.path.dirname(HERE),
               STICKSLIP_URL=lenient.url)
    out = subprocess.run([sys.executable, "-c", code], env=env,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, "%s:%d: %s" % (page, line, out.stderr)
    if want is not None:
        assert out.stdout == want, "%s:%d" % (page, line)
