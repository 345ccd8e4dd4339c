"""Jobs against the live daemon (POST with Prefer: respond-async -> 201 +
Location; GET /jobs/{id}, its status; GET /jobs/{id}/results, the
synchronous answer; DELETE /jobs/{id}): an /orbit and a /batch, progress,
the plain progress line, results resumed after a cut, a dismissal, a failed
job.  A fake server in the test process plays a job whose status moves one
item a poll.  And a daemon without jobs: the request is answered at once."""

from __future__ import annotations

import io
import re
import time
from typing import Any, Callable, Dict, List

import pytest

import stickslip
from stickslip.progress import Progress
from conftest import PAPER, Daemon
from fake import FakeServer
from proxy import CuttingProxy

LINES = [{"id": i, "index": i, "status": 200, "body": {"n": i}}
         for i in range(4)] + [{"done": True, "ok": 4, "failed": 0}]


def jobs_routes(state: Dict[str, Any]) -> Dict[Any, Any]:
    def submit(body: Any) -> Any:
        state["body"] = body
        return (201, {"Location": "/jobs/j1",
                      "Content-Type": "application/json"},
                b'{"jobID":"j1","status":"accepted","progress":0,'
                b'"items":{"done":0,"total":4}}')

    def status(_: Any) -> Any:
        state["polls"] += 1
        done = min(4, state["polls"])
        return {"jobID": "j1", "progress": 25 * done,
                "status": "successful" if done == 4 else "running",
                "items": {"done": done, "total": 4}}

    def results(_: Any) -> Any:
        state["reads"] += 1
        import json
        data = b"".join(json.dumps(x).encode() + b"\n" for x in LINES)
        headers = {"Content-Type": "application/x-ndjson"}
        if state["reads"] == 1:
            headers["X-Cut"] = str(data.index(b"\n", 40) + 5)
        return (200, headers, data)

    def dismiss(_: Any) -> Any:
        state["deleted"] = True
        return {"jobID": "j1", "status": "dismissed"}

    return {("POST", "/batch"): submit, ("GET", "/jobs/j1"): status,
            ("GET", "/jobs/j1/results"): results,
            ("DELETE", "/jobs/j1"): dismiss}


def test_submit_wait_results_cancel(monkeypatch: Any) -> None:
    state: Dict[str, Any] = {"polls": 0, "reads": 0}
    with FakeServer(jobs_routes(state)) as fake:
        c = stickslip.Client(fake.url)
        job = c.submit("/batch", requests=[{"path": "/orbit", "body": {}}])
        assert fake.log[0][2]["Prefer"] == "respond-async"
        assert state["body"] == {"requests": [{"path": "/orbit",
                                               "body": {}}]}
        assert job.id == "j1" and job.progress == 0
        err = io.StringIO()
        monkeypatch.setattr("sys.stderr", err)
        monkeypatch.setitem(__import__("sys").modules, "tqdm", None)
        monkeypatch.setitem(__import__("sys").modules, "tqdm.auto", None)
        final = job.wait(progress=True, poll=0.01)
        assert final["status"] == "successful" and job.progress == 100
        assert "job j1: 4/4 (100%)" in err.getvalue()
        lines = job.results()
        got = list(lines)
        # the stream was cut after the first line: read again, no line twice
        assert state["reads"] == 2
        assert got == LINES[:-1] and lines.done == LINES[-1]
        job.cancel()
        assert state["deleted"] and job.last["status"] == "dismissed"


def test_wait_with_tqdm(monkeypatch: Any) -> None:
    """tqdm installed: wait(progress=True) draws its bar of the items."""
    pytest.importorskip("tqdm")
    err = io.StringIO()
    monkeypatch.setattr("sys.stderr", err)
    with FakeServer(jobs_routes({"polls": 0, "reads": 0})) as fake:
        job = stickslip.Client(fake.url).submit("/batch", requests=[])
        job.wait(progress=True, poll=0.01)
    assert re.search(r"job j1: 100%\|[^|]*\| 4/4 \[", err.getvalue()), \
        err.getvalue()


def test_plain_line_on_a_terminal(monkeypatch: Any) -> None:
    """Without tqdm, on a terminal: one line rewritten in place at each
    step, ended when the bar closes; in a log, a line every tenth."""
    no_tqdm(monkeypatch)

    class Tty(io.StringIO):
        def isatty(self) -> bool:
            return True
    for stream, want in ((Tty(), "\rsweep: 0/4 (0%)\rsweep: 1/4 (25%)"
                          "\rsweep: 2/4 (50%)\rsweep: 3/4 (75%)"
                          "\rsweep: 4/4 (100%)\n"),
                         (io.StringIO(), "".join(
                             "sweep: %d/20 (%d%%)\n" % (n, 5 * n)
                             for n in range(0, 21, 2)))):
        bar = Progress(4 if want.startswith("\r") else 20, "sweep",
                       stream=stream)
        for _ in range(bar.total or 0):
            bar.update()
        bar.close()
        assert stream.getvalue() == want


def test_failed_job_raises() -> None:
    def status(_: Any) -> Any:
        return {"jobID": "j1", "status": "failed", "progress": 50}
    routes = jobs_routes({"polls": 0, "reads": 0})
    routes[("GET", "/jobs/j1")] = status
    with FakeServer(routes) as fake:
        job = stickslip.Client(fake.url).submit("/batch", {"requests": []})
        try:
            job.wait(progress=False, poll=0.01)
        except stickslip.JobFailed as e:
            assert e.status["status"] == "failed"
        else:
            raise AssertionError("a failed job returned")


def test_daemon_without_jobs_answers_at_once(
        start: Callable[..., Daemon], client: stickslip.Client) -> None:
    d = start("--no-jobs")
    job = d.client().submit("/orbit", params=PAPER, kind="overshoot")
    assert job.id is None and job.status()["status"] == "successful"
    answer: List[Any] = list(job.results())
    assert answer[0]["orbits"] == client.orbit(
        params=PAPER, kind="overshoot")["orbits"]
    lines = d.client().submit("/batch", requests=[
        {"path": "/orbit", "body": {"params": PAPER}}]).results()
    assert [x["status"] for x in lines] == [200] and lines.done is not None


def test_synchronous_batch_gathered_by_index() -> None:
    """A /batch answered at once (a daemon without jobs) is gathered in the
    order of its items, whatever order they finished in."""
    shuffled = [LINES[2], LINES[0], LINES[3], LINES[1], LINES[4]]
    with FakeServer({("POST", "/batch"): lambda _: shuffled}) as fake:
        job = stickslip.Client(fake.url).submit("/batch", requests=[])
        assert job.id is None
        assert [x["index"] for x in job.results().gather()] == [0, 1, 2, 3]


# the stick -> slip point of the paper's orbit; a motion from it to this
# t_end takes a few hundredths of a second
X0 = [1.2739277342427062, 4.3629277342427093, -0.80748713672430694, 1.0]


def slow_batch(n: int, t_end: float = 4e5) -> List[Dict[str, Any]]:
    return [{"id": i, "path": "/simulate",
             "body": {"params": PAPER, "initial": X0, "t_end": t_end,
                      "events": False}} for i in range(n)]


def no_tqdm(monkeypatch: Any) -> io.StringIO:
    """stderr as a string, and tqdm absent: the plain progress line."""
    err = io.StringIO()
    monkeypatch.setattr("sys.stderr", err)
    monkeypatch.setitem(__import__("sys").modules, "tqdm", None)
    monkeypatch.setitem(__import__("sys").modules, "tqdm.auto", None)
    return err


def without_seconds(done: Any) -> Any:
    return {k: v for k, v in done.items() if k != "seconds"}


def test_orbit_job(client: stickslip.Client) -> None:
    job = client.submit("/orbit", params=PAPER, kind="overshoot")
    assert job.id is not None and re.fullmatch(r"[0-9a-f]{32}", job.id)
    assert job.location == "/jobs/" + job.id
    st = job.status()
    assert st["id"] == job.id and st["path"] == "/orbit"
    assert st["processID"] == "orbit"
    assert st["status"] in ("accepted", "running", "successful")
    assert st["items"]["total"] == 1
    final = job.wait(progress=False, poll=0.02, timeout=30)
    assert final["status"] == "successful" and job.progress == 100
    assert final["items"] == {"done": 1, "total": 1}
    assert list(job.results()) == [client.orbit(params=PAPER,
                                                kind="overshoot")]


def test_batch_job_progress_and_results(client: stickslip.Client,
                                        monkeypatch: Any) -> None:
    reqs = slow_batch(96)
    job = client.submit("/batch", requests=reqs)
    assert job.last["status"] == "accepted" and job.progress == 0
    assert job.last["items"] == {"done": 0, "total": 96}
    seen = [job.progress]
    while job.status()["status"] in ("accepted", "running"):
        seen.append(job.progress)
        time.sleep(0.02)
    assert job.last["status"] == "successful"
    seen.append(job.progress)
    assert seen == sorted(seen) and seen[-1] == 100
    assert len(set(seen)) >= 3  # seen between its start and its end
    assert job.last["items"] == {"done": 96, "total": 96}
    lines = job.results()
    got = list(lines)
    assert [x["index"] for x in got] == list(range(96))  # in index order
    sync = client.batch(reqs)
    assert got == sync.gather()
    assert lines.done is not None and sync.done is not None
    assert without_seconds(lines.done) == without_seconds(sync.done)
    # wait() on a running job: the plain line moves to its items' total
    err = no_tqdm(monkeypatch)
    job = client.submit("/batch", requests=reqs)
    job.wait(progress=True, poll=0.02, timeout=60)
    shown = re.findall(r"job %s: (\d+)/96 \((\d+)%%\)" % job.id,
                       err.getvalue())
    assert len(shown) >= 2 and shown[-1] == ("96", "100")
    assert [int(n) for n, _ in shown] == sorted(int(n) for n, _ in shown)


def test_results_cut_resumed(daemon: Daemon) -> None:
    proxy = CuttingProxy(daemon.url, keep=5, when=b"/results")
    reqs = slow_batch(40, 1e5)
    job = stickslip.Client(proxy.url).submit("/batch", requests=reqs)
    lines = job.results()  # streamed while the job runs, cut after 5 lines
    got = list(lines)
    assert len(proxy.requests) == 2  # asked again once
    assert [x["index"] for x in got] == list(range(40))
    whole = daemon.client().batch(reqs)
    assert got == whole.gather()
    assert lines.done is not None and whole.done is not None
    assert without_seconds(lines.done) == without_seconds(whole.done)


def test_cancel_running_job(client: stickslip.Client) -> None:
    job = client.submit("/batch", requests=slow_batch(512))
    while job.status()["status"] != "running":
        time.sleep(0.02)
    st = job.cancel()
    assert st["status"] == "dismissed" and job.last is st
    assert job.status()["status"] == "dismissed"
    with pytest.raises(stickslip.NotFound) as info:
        list(job.results())
    assert type(info.value) is stickslip.NotFound
    assert info.value.status == 404 and info.value.kind == "not-found"
    with pytest.raises(stickslip.JobFailed) as failed:
        job.wait(progress=False)
    assert failed.value.status["status"] == "dismissed"


def test_failed_job_results_raise(start: Callable[..., Daemon]) -> None:
    """A job over --job-max-seconds fails; its results are its problem."""
    c = start("--job-max-seconds", "0.1").client()
    job = c.submit("/simulate", params=PAPER, initial=X0, t_end=9e6,
                   events=False)
    with pytest.raises(stickslip.JobFailed) as info:
        job.wait(progress=False, poll=0.02, timeout=30)
    assert info.value.status["status"] == "failed"
    assert info.value.status["message"]
    with pytest.raises(stickslip.RequestOverLimit):
        list(job.results())
