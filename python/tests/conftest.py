"""The daemon the tests run against: STICKSLIPD in the environment or
``--stickslipd PATH`` (CTest passes the one it built); each started on a
free port (``--port 0``), its URL read from its first line on stderr, with
a job store of its own in a temporary directory (unless its flags name
one, or --no-jobs)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tempfile
from typing import Iterator, List

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

import stickslip  # noqa: E402

PAPER = {"chi": 0.2, "eta": 4, "us": 0.0724, "ur": 0.6178, "V": 1}


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--stickslipd", default=os.environ.get("STICKSLIPD"))


class Daemon:
    def __init__(self, binary: str, flags: List[str]) -> None:
        self.tmp = tempfile.mkdtemp(prefix="stickslip-py-")
        if "--no-jobs" not in flags and "--job-store" not in flags:
            flags = ["--job-store",
                     "sqlite:" + os.path.join(self.tmp, "jobs.sqlite"),
                     *flags]
        self.proc = subprocess.Popen([binary, "--port", "0", "--quiet",
                                      "--state-dir", self.tmp, *flags],
                                     stderr=subprocess.PIPE, text=True)
        assert self.proc.stderr is not None
        said = ""
        m = None
        while m is None:  # notes (a store that cannot be opened) come first
            line = self.proc.stderr.readline()
            said += line
            m = re.search(r"http://[^ \n]+", line)
            if not line:
                self.proc.kill()
                raise RuntimeError("stickslipd did not start: " + said)
        self.url = m.group(0).rstrip("/")

    def client(self, **kw: object) -> stickslip.Client:
        return stickslip.Client(self.url, **kw)  # type: ignore[arg-type]

    def metric(self, name: str, **labels: str) -> float:
        """The sum of a metric's samples whose labels include ``labels``."""
        total = 0.0
        for line in self.client().metrics().splitlines():
            if not line.startswith(name):
                continue
            head, value = line.rsplit(" ", 1)
            if head != name and not head.startswith(name + "{"):
                continue
            if all('%s="%s"' % kv in head for kv in labels.items()):
                total += float(value)
        return total

    def stop(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        shutil.rmtree(self.tmp, ignore_errors=True)


@pytest.fixture(scope="session")
def binary(request: pytest.FixtureRequest) -> str:
    path = request.config.getoption("--stickslipd")
    if not path or not os.access(path, os.X_OK):
        pytest.skip("no stickslipd: set STICKSLIPD or --stickslipd")
    return str(path)


@pytest.fixture(scope="session")
def daemon(binary: str) -> Iterator[Daemon]:
    d = Daemon(binary, [])
    yield d
    d.stop()


@pytest.fixture
def start(binary: str) -> Iterator["object"]:
    """start(*flags): a daemon of its own for one test."""
    started: List[Daemon] = []

    def run(*flags: str) -> Daemon:
        d = Daemon(binary, list(flags))
        started.append(d)
        return d

    yield run
    for d in started:
        d.stop()


@pytest.fixture
def client(daemon: Daemon) -> stickslip.Client:
    return daemon.client()
