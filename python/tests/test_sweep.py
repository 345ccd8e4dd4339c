"""Sweeps, as /batch jobs and as batches (a daemon with --no-jobs):
results in the items' order, under the daemon's limits, interrupted and
resumed, counted at the daemon: as jobs, no item computed twice (the
chunks it computed, stickslip_job_chunks_total, are the one job's); as
batches, no item of the journal computed again (stickslip_batch_items_total;
the items in flight when the first sweep was killed are computed again,
their lines lost with it); a torn journal, 503 lines sent again."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from typing import Any, Callable, Dict, List, Tuple

import stickslip
from conftest import HERE, PAPER, Daemon
from fake import FakeServer


def items(n: int) -> List[Dict[str, Any]]:
    return [{"params": dict(PAPER, ur=0.45 + 0.005 * i), "kind": "all"}
            for i in range(n)]


def computed(d: Daemon) -> float:
    return d.metric("stickslip_batch_items_total", endpoint="orbit")


def test_results_in_order_under_limits(start: Callable[..., Daemon],
                                       client: stickslip.Client) -> None:
    d = start("--no-jobs", "--max-batch-items", "4", "--max-body", "1200")
    named = [{"id": "p%d" % i, "body": b} for i, b in enumerate(items(11))]
    got = d.client().sweep(named)
    assert [r["id"] for r in got] == ["p%d" % i for i in range(11)]
    for r, b in zip(got, items(11)):
        assert r["status"] == 200
        assert r["body"]["orbits"] == client.orbit(b)["orbits"]
    # each item computed once, in batches the daemon took
    assert computed(d) == 11
    assert d.metric("stickslip_requests_total", endpoint="batch",
                    code="200") >= 3


def jobs_of(d: Daemon) -> List[Dict[str, Any]]:
    listed: List[Dict[str, Any]] = d.client().request(
        "GET", "/jobs?limit=1000")["jobs"]
    return listed


def test_jobs_in_order_under_limits(start: Callable[..., Daemon],
                                    client: stickslip.Client) -> None:
    """The job limits, past the synchronous ones: cut under the ones the
    daemon names (max_batch_items for the items of a job, max_job_body)."""
    d = start("--max-batch-items", "2", "--max-body", "100",
              "--max-job-items", "5", "--max-job-body", "1200")
    named = [{"id": "p%d" % i, "body": b} for i, b in enumerate(items(11))]
    got = d.client().sweep(named)
    assert [r["id"] for r in got] == ["p%d" % i for i in range(11)]
    for r, b in zip(got, items(11)):
        assert r["status"] == 200
        assert r["body"]["orbits"] == client.orbit(b)["orbits"]
    jobs = jobs_of(d)
    sizes = [j["items"]["total"] for j in reversed(jobs)]  # oldest first
    assert sum(sizes) == 11 and len(jobs) >= 3
    assert all(2 < n <= 5 for n in sizes[:-1])  # past the synchronous limit
    assert all(j["path"] == "/batch" and j["status"] == "successful"
               for j in jobs)
    assert computed(d) == 0  # no synchronous batch


def test_problem_items_are_results(client: stickslip.Client) -> None:
    got = client.sweep([{"params": PAPER, "kind": "overshoot"},
                        {"params": dict(PAPER, chi=-1)}])
    assert [r["id"] for r in got] == [0, 1]
    assert got[0]["status"] == 200 and got[1]["status"] == 422
    assert got[1]["body"]["pointer"] == "/body/params/chi"


SCRIPT = """
import sys, json
sys.path.insert(0, %r)
import stickslip
items = json.load(open(sys.argv[2]))
stickslip.Client(sys.argv[1]).sweep(items, journal=sys.argv[3])
"""


def interrupted(d: Daemon, todo: List[Any], tmp_path: Any) -> Tuple[str, int]:
    """A sweep of ``todo`` in another process, killed once its journal
    holds 10 results, and a torn line appended: the journal, and the
    results it kept."""
    (tmp_path / "items.json").write_text(json.dumps(todo))
    journal = str(tmp_path / "sweep.jsonl")
    proc = subprocess.Popen([sys.executable, "-c",
                             SCRIPT % os.path.dirname(HERE), d.url,
                             str(tmp_path / "items.json"), journal])
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if os.path.exists(journal) and \
                open(journal).read().count('"request":') >= 10:
            break
        time.sleep(0.005)
    proc.kill()
    proc.wait()
    with open(journal, "a") as f:
        f.write('{"id": 59, "status": 2')  # a torn last line
    kept = open(journal).read().count('"request":')
    assert 10 <= kept < len(todo)
    return journal, kept


def test_interrupted_and_resumed(start: Callable[..., Daemon],
                                 tmp_path: Any) -> None:
    d = start("--no-jobs", "--batch-parallel", "1")
    todo = items(60)
    journal, kept = interrupted(d, todo, tmp_path)
    time.sleep(0.5)  # the items in flight at the kill are done or cancelled
    first = computed(d)
    got = d.client().sweep(todo, journal=journal)
    # the second run computed exactly the items the journal lacked
    assert computed(d) - first == 60 - kept
    assert [r["id"] for r in got] == list(range(60))
    assert all(r["status"] == 200 for r in got)
    lines = open(journal).read().splitlines()
    assert len(lines) == 61 and json.loads(lines[0])["path"] == "/orbit"
    # a third run computes nothing; a changed body is computed again
    again = d.client().sweep(todo, journal=journal)
    assert again == got and computed(d) - first == 60 - kept
    todo[5] = dict(todo[5], kind="overshoot")
    d.client().sweep(todo, journal=journal)
    assert computed(d) - first == 60 - kept + 1


def chunks(d: Daemon) -> float:
    return d.metric("stickslip_job_chunks_total")


def test_job_interrupted_and_resumed(start: Callable[..., Daemon],
                                     client: stickslip.Client,
                                     tmp_path: Any) -> None:
    """The job goes on when its sweep is killed; the second sweep reads
    its results: one job, each of its chunks computed once."""
    d = start()
    todo = items(150)
    journal, kept = interrupted(d, todo, tmp_path)
    got = d.client().sweep(todo, journal=journal)
    jobs = jobs_of(d)
    assert len(jobs) == 1 and jobs[0]["items"]["total"] == 150
    assert chunks(d) == jobs[0]["chunks"]["total"]
    assert [r["id"] for r in got] == list(range(150))
    assert all(r["status"] == 200 for r in got)
    assert got[140]["body"]["orbits"] == client.orbit(todo[140])["orbits"]
    lines = open(journal).read().splitlines()
    assert len(lines) == 1 + 1 + 150  # the header, the job, the results
    # a third run computes nothing; a changed body is a job of one item
    assert d.client().sweep(todo, journal=journal) == got
    assert len(jobs_of(d)) == 1
    todo[5] = dict(todo[5], kind="overshoot")
    again = d.client().sweep(todo, journal=journal)
    assert again[5]["body"] == client.orbit(todo[5])
    assert [j["items"]["total"] for j in jobs_of(d)] == [1, 150]


def test_job_gone_sent_again(start: Callable[..., Daemon],
                             tmp_path: Any) -> None:
    """A journaled job the daemon no longer has (dismissed): the items it
    had not answered are sent again, and only those."""
    d = start()
    todo = items(150)
    journal, kept = interrupted(d, todo, tmp_path)
    job = jobs_of(d)[0]
    d.client().request("DELETE", "/jobs/" + job["id"])
    got = d.client().sweep(todo, journal=journal)
    assert all(r["status"] == 200 for r in got)
    jobs = jobs_of(d)
    assert len(jobs) == 2 and jobs[0]["items"]["total"] == 150 - kept


def test_sweep_without_jobs_on_a_store_unavailable(
        start: Callable[..., Daemon]) -> None:
    d = start("--job-store", "sqlite:/dev/null/no/jobs.sqlite")
    got = stickslip.Client(d.url, retries=0).sweep(items(3))
    assert [r["status"] for r in got] == [200] * 3 and computed(d) == 3


def test_503_lines_sent_again(monkeypatch: Any) -> None:
    """A batch whose second item is answered 503 (the daemon's queue full
    with none of the batch in flight; provoked here by a fake server in the
    test process, which answers each item's line itself)."""
    seen: List[List[Any]] = []

    def batch(body: Dict[str, Any]) -> List[Dict[str, Any]]:
        reqs = body["requests"]
        seen.append([r["body"]["n"] for r in reqs])
        lines = []
        for i, r in enumerate(reqs):
            busy = r["body"]["n"] == 1 and len(seen) == 1
            lines.append({"id": None, "index": i,
                          "status": 503 if busy else 200,
                          "body": {"type": "/problems/overloaded"} if busy
                          else {"twice": 2 * r["body"]["n"]}})
        return lines + [{"done": True}]

    with FakeServer({("POST", "/batch"): batch}) as fake:
        monkeypatch.setattr("stickslip.sweep.RETRY_DELAY", 0.01)
        got = stickslip.Client(fake.url).sweep(
            [{"n": i} for i in range(3)], path="/x")
    assert seen == [[0, 1, 2], [1]]
    assert [r["body"]["twice"] for r in got] == [0, 2, 4]
