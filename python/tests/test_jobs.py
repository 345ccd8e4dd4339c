"""Jobs against a fake server in the test process that follows the jobs
service's description (POST with Prefer: respond-async -> 201 + Location;
GET /jobs/{id} status with progress and items; GET /jobs/{id}/results;
DELETE /jobs/{id}); the live daemon's jobs are tested when it has them.
And a daemon without jobs: the request is answered at once."""

from __future__ import annotations

import io
from typing import Any, Callable, Dict, List

import stickslip
from conftest import PAPER, Daemon
from fake import FakeServer

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
