"""Jobs that are never lost: ``kill -9`` of the server during a burst of runs, then a
restart; every accepted job ends in a terminal state, none lost and none done twice."""

from __future__ import annotations

import sqlite3
import time
from pathlib import Path

import pytest

from llm_grop.errors import BadInput
from llm_grop.service.jobs import MAX_ATTEMPTS, JobStore
from service_support import start_server, wait_done


def test_kill_9_during_a_burst_then_restart(tmp_path: Path) -> None:
    db = tmp_path / "jobs.sqlite"
    server = start_server(db, "--workers", "2")
    accepted = []
    with server.client() as c:
        for seed in range(12):
            r = c.post("/v1/runs", json={"task": 8, "seed": seed})
            assert r.status_code in (202, 429)
            if r.status_code == 202:
                accepted.append(r.json()["id"])
        time.sleep(0.8)  # some running, some done, some waiting
    server.kill()
    before = {r[0]: (r[1], r[2]) for r in sqlite3.connect(db).execute(
        "SELECT id, state, finished FROM jobs")}
    assert set(before) == set(accepted)
    states = [state for state, _ in before.values()]
    assert "queued" in states or "running" in states

    again = start_server(db, "--workers", "2")
    try:
        with again.client() as c:
            final = [wait_done(c, job_id) for job_id in accepted]
    finally:
        again.stop()
    assert [j["state"] for j in final] == ["done"] * len(accepted)
    assert len(sqlite3.connect(db).execute("SELECT id FROM jobs").fetchall()) == len(accepted)
    for j in final:
        state, finished = before[j["id"]]
        if state == "done":  # kept its first result: a restart runs nothing twice
            assert j["attempts"] == 1 and j["finished"] == finished
        else:  # run once more, and only once
            assert j["attempts"] == (2 if state == "running" else 1)


def test_a_second_server_on_one_database_is_refused(tmp_path: Path) -> None:
    from llm_grop.service.http import hold_lock

    db = tmp_path / "jobs.sqlite"
    fd = hold_lock(db)
    try:
        with pytest.raises(BadInput, match=r"in use by another llm-grop serve \(pid \d+\)"):
            hold_lock(db)
    finally:
        import os

        os.close(fd)
    os.close(hold_lock(db))  # free once its holder let go


def test_a_stale_worker_cannot_write_a_result(tmp_path: Path) -> None:
    store = JobStore(tmp_path / "jobs.sqlite")
    job_id = store.submit("run", {"task": 8}, "me", queue=10)
    first = store.claim(worker=1)
    assert first is not None and first.id == job_id
    assert store.recover() == 1  # the server restarted under it
    second = store.claim(worker=2)
    assert second is not None and second.claim != first.claim
    assert not store.finish(first, {"run": "stale"}, {})
    assert not store.fail(first, 500, "stale")
    store.event(first, "stale")
    assert [m for _, _, m in store.events(job_id)] == [
        "attempt 2 of 3, after the last one was interrupted"]
    assert store.finish(second, {"run": "fresh"}, {"a.png": ("image/png", b"x")})
    done = store.get(job_id)
    assert done is not None and done.state == "done" and done.result == {"run": "fresh"}
    assert done.attempts == 2


def test_a_job_that_keeps_killing_its_worker_fails_with_a_reason(tmp_path: Path) -> None:
    store = JobStore(tmp_path / "jobs.sqlite")
    job_id = store.submit("run", {"task": 8}, "me", queue=10)
    for _ in range(MAX_ATTEMPTS):
        job = store.claim(worker=1)
        assert job is not None
        store.orphaned(job, "its worker died")
    job = store.get(job_id)
    assert job is not None and job.state == "failed"
    assert job.error == f"its worker died {MAX_ATTEMPTS} times; given up"


def test_the_queue_is_bounded(tmp_path: Path) -> None:
    from llm_grop.service.jobs import Overloaded

    store = JobStore(tmp_path / "jobs.sqlite")
    for _ in range(3):
        store.submit("arrange", {}, "me", queue=3)
    with pytest.raises(Overloaded, match="3 jobs are waiting"):
        store.submit("arrange", {}, "you", queue=3)
    store.submit("run", {}, "me", queue=10, per_client=1)
    with pytest.raises(Overloaded, match="1 of your runs are unfinished"):
        store.submit("run", {}, "me", queue=10, per_client=1)


def test_ended_jobs_are_pruned_after_the_keep_time_with_their_files(tmp_path: Path) -> None:
    from llm_grop.service.config import ServiceConfig
    from llm_grop.service.workers import WorkerPool

    db = tmp_path / "jobs.sqlite"
    store = JobStore(db)
    old, recent, waiting = (store.submit("run", {"task": k}, "me", queue=10)
                            for k in range(3))
    for _ in range(2):
        job = store.claim(worker=1)
        assert job is not None
        store.event(job, "working")
        assert store.finish(job, {"run": job.id}, {"a.png": ("image/png", b"x")})
    with store.connection() as conn:
        conn.execute("UPDATE jobs SET finished = ? WHERE id = ?",
                     (time.time() - 40 * 86400, old))
    # The supervisor's round prunes what ended more than keep_s ago, nothing else.
    pool = WorkerPool(ServiceConfig(db=db, backends=(), keep_s=30 * 86400))
    pool._store = store
    pool._round()
    assert store.get(old) is None and store.file(old, "a.png") is None
    assert store.events(old) == []
    assert [store.get(j).state for j in (recent, waiting)] == [  # type: ignore[union-attr]
        "done", "queued"]
    assert store.file(recent, "a.png") == ("image/png", b"x")
    running = store.claim(worker=1)
    assert running is not None and running.id == waiting
    assert store.prune(time.time() + 1) == 1  # the recent one; never a running job
    assert store.get(waiting) is not None and store.get(recent) is None
    store.close()


def test_pruning_goes_a_batch_at_a_time(tmp_path: Path) -> None:
    store = JobStore(tmp_path / "jobs.sqlite")
    ids = [store.submit("arrange", {"k": k}, "me", queue=10) for k in range(5)]
    for _ in ids:
        job = store.claim(worker=1)
        assert job is not None and store.finish(job, {}, {})
    assert store.prune(time.time() + 1, batch=2) == 5
    assert all(store.get(j) is None for j in ids)
    store.close()


def test_each_thread_has_a_connection_and_a_waiting_writer_holds_up_no_reader(
        tmp_path: Path) -> None:
    import threading

    db = tmp_path / "jobs.sqlite"
    store = JobStore(db)
    job_id = store.submit("run", {"task": 8}, "me", queue=10)
    holder = sqlite3.connect(db, isolation_level=None)
    holder.execute("BEGIN IMMEDIATE")  # a worker's long commit holds the write lock
    submitted: list[str] = []
    writer = threading.Thread(target=lambda: submitted.append(
        store.submit("run", {"task": 1}, "me", queue=10)))
    writer.start()
    time.sleep(0.3)  # lets the writer reach its BEGIN and wait there
    try:
        # The writer waits for the lock in its thread; a read in this one is answered.
        job = store.get(job_id)
        assert job is not None and job.state == "queued" and not submitted
    finally:
        holder.execute("COMMIT")
        holder.close()
    writer.join(timeout=30)
    assert len(submitted) == 1 and store.get(submitted[0]) is not None
    store.close()


def test_a_database_of_the_first_schema_is_migrated_keeping_every_job(tmp_path: Path
                                                                      ) -> None:
    """Schema 2 adds the ``learn`` kind by rebuilding the tables: a job's files and events
    must survive it (dropping the jobs table first would cascade them away)."""
    from llm_grop import database
    from llm_grop.service.jobs import JOBS

    db = tmp_path / "jobs.sqlite"
    conn = database.connect(JOBS, db, create=True, upto=1)
    conn.execute("INSERT INTO jobs (id, kind, body, client, priority, state, created, result) "
                 "VALUES ('r1', 'run', '{}', 'c', 1, 'done', 1.0, '{\"run\": {}}')")
    conn.execute("INSERT INTO files VALUES ('r1', 'table.png', 'image/png', x'89504e47')")
    conn.execute("INSERT INTO events VALUES ('r1', 1, 1.0, 'executing the plan')")
    with pytest.raises(sqlite3.IntegrityError):
        conn.execute("INSERT INTO jobs (id, kind, body, client, priority, state, created) "
                     "VALUES ('l0', 'learn', '{}', 'c', 0, 'queued', 1.0)")
    conn.close()
    store = JobStore(db)
    try:
        job = store.get("r1")
        assert job is not None and (job.kind, job.state, job.result) == ("run", "done",
                                                                         {"run": {}})
        assert store.file("r1", "table.png") == ("image/png", b"\x89PNG")
        assert [m for _, _, m in store.events("r1")] == ["executing the plan"]
        learn = store.submit("learn", {"examples": []}, "c", queue=10, per_client=10)
        assert store.get(learn).kind == "learn"  # type: ignore[union-attr]
        with store.connection() as c:
            assert c.execute("PRAGMA foreign_key_check").fetchall() == []
            c.execute("DELETE FROM jobs WHERE id = 'r1'")  # its files and events go with it
            assert c.execute("SELECT count(*) FROM files").fetchone()[0] == 0
            assert c.execute("SELECT count(*) FROM events").fetchone()[0] == 0
    finally:
        store.close()
