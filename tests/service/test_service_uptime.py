"""A service that holds for weeks (issue 37): its open files stay bounded however often
its thread pool retires threads, and a full or read-only disk refuses new work with 503
and ``Retry-After`` while the workers wait, without a traceback, and run what was accepted
once the disk takes writes again.

The disks are small tmpfs mounts in a user namespace of their own (:mod:`small_disk`);
where none can be made those tests are skipped, saying why."""

from __future__ import annotations

import errno
import json
import logging
import os
import sqlite3
import subprocess
import sys
import threading
import time
from pathlib import Path

import httpx
import pytest

from llm_grop import database
from llm_grop.service.jobs import CONNECTIONS, JOBS, JobStore
from llm_grop.service.storage import LONGEST_WAIT_S, MESSAGES, Backoff, problem
from service_support import free_port, wait_done
from small_disk import SmallDisk, unavailable
from uptime_support import (
    alive,
    burst,
    descriptors,
    serve_command,
    server_env,
    wait_answering,
)

#: Bursts of requests, each followed by enough quiet for the server's threads to retire.
CYCLES = 50
#: Descriptors the database may hold open: each pooled connection has the file and its
#: WAL, in the app's pool and the supervisor's (one: it has one thread); and the shared
#: memory and lock files.
DB_FILES = 2 * (CONNECTIONS + 1) + 2


def test_descriptors_stay_bounded_over_idle_cycles(tmp_path: Path) -> None:
    db, port = tmp_path / "jobs.sqlite", free_port()
    with (tmp_path / "serve.log").open("ab") as log:
        # The pool's threads retire after 0.05 s idle instead of anyio's 10 s.
        proc = subprocess.Popen(serve_command(db, port, "--workers", "1",
                                              thread_idle_s=0.05),
                                env=server_env(), stdout=log, stderr=log)
    url = f"http://127.0.0.1:{port}"
    try:
        wait_answering(url, lambda: proc.poll() is None)
        counts = []
        for _ in range(CYCLES):
            assert burst(url, 40) == {200: 40}
            time.sleep(0.15)  # every thread idles longer than the pool keeps it
            counts.append(descriptors(proc.pid, db.name))
    finally:
        proc.terminate()
        proc.wait(timeout=30)
    totals = [total for total, _ in counts]
    # The connection pool may grow to its size (two files a connection) when a burst
    # finds more of its threads at once than before; nothing else is opened, however many
    # threads come and go (before, each burst's new threads left about 50 behind).
    assert max(totals) - totals[0] <= 2 * CONNECTIONS, totals
    assert max(on for _, on in counts) <= DB_FILES, counts


def test_threads_that_end_leave_no_connection_open(tmp_path: Path) -> None:
    db = tmp_path / "jobs.sqlite"
    store = JobStore(db)
    job_id = store.submit("run", {"task": 8}, "me", queue=10)
    start = threading.Barrier(30)

    def reader() -> None:
        start.wait()
        assert store.get(job_id) is not None

    for _ in range(3):
        threads = [threading.Thread(target=reader) for _ in range(30)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    assert descriptors(os.getpid(), db.name)[1] <= 2 * CONNECTIONS + 1  # and its memory
    store.close()
    assert descriptors(os.getpid(), db.name)[1] == 0


def test_a_commit_that_fails_leaves_no_transaction_open(tmp_path: Path) -> None:
    conn = database.connect(JOBS, tmp_path / "jobs.sqlite", create=True)
    conn.execute("PRAGMA defer_foreign_keys = ON")  # checked at COMMIT, which fails
    with pytest.raises(sqlite3.IntegrityError), database.transaction(conn) as c:
        c.execute("INSERT INTO events (job, seq, at, message) VALUES ('none', 1, 0, 'x')")
    assert not conn.in_transaction  # else it would hold the write lock for good
    conn.close()


def test_the_disk_refusing_a_write_is_told_from_other_errors(tmp_path: Path) -> None:
    db = tmp_path / "jobs.sqlite"
    store = JobStore(db)
    with store.connection() as conn:
        conn.execute("PRAGMA max_page_count = 8")  # a database that cannot grow: SQLITE_FULL
        with pytest.raises(sqlite3.OperationalError) as full:
            conn.execute("INSERT INTO jobs (id, kind, body, client, priority, state, created) "
                         "VALUES ('a', 'run', ?, 'me', 1, 'queued', 0)", ("x" * 100_000,))
    read_only = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    with pytest.raises(sqlite3.OperationalError) as refused:
        read_only.execute("DELETE FROM jobs")
    read_only.close()
    with pytest.raises(sqlite3.OperationalError) as other:
        sqlite3.connect(db).execute("SELECT nope FROM jobs")
    assert problem(full.value, tmp_path) == "full"
    assert problem(refused.value, tmp_path) == "read_only"
    assert problem(other.value, tmp_path) is None
    try:
        raise RuntimeError("could not write the picture") from OSError(errno.ENOSPC, "full")
    except RuntimeError as wrapped:
        assert problem(wrapped, tmp_path) == "full"
    assert problem(OSError(errno.EROFS, "read-only"), tmp_path) == "read_only"
    assert problem(OSError(errno.ENOENT, "gone"), tmp_path) is None
    store.close()


def test_backoff_is_bounded_and_logged_once_an_episode(caplog: pytest.LogCaptureFixture
                                                       ) -> None:
    backoff = Backoff("worker 1", logging.getLogger("llm_grop.test"))
    with caplog.at_level(logging.WARNING, logger="llm_grop.test"):
        waits = [backoff.wait_s("full") for _ in range(12)]
        backoff.cleared()
        again = backoff.wait_s("read_only")
    assert waits[:3] == [0.1, 0.2, 0.4] and max(waits) == LONGEST_WAIT_S
    assert again == 0.1
    assert [r.getMessage() for r in caplog.records] == [
        "worker 1: the disk holding the jobs is full; waiting for it",
        caplog.records[1].getMessage(),
        "worker 1: the disk holding the jobs is read-only; waiting for it"]
    assert caplog.records[1].getMessage().startswith("worker 1: the disk takes writes again")


@pytest.fixture
def small_disk(tmp_path: Path) -> SmallDisk:
    why = unavailable()
    if why is not None:
        pytest.skip(f"no small disk: {why}")
    # Room for two runs' files, their pictures and recordings (episode.rrd) included.
    with SmallDisk(tmp_path / "data", 3072) as disk:
        yield disk


def _serve(disk: SmallDisk, db: Path, log: Path) -> tuple[int, str]:
    port = free_port()
    pid = disk.start(serve_command(db, port, "--workers", "1"), log, server_env())
    url = f"http://127.0.0.1:{port}"
    wait_answering(url, lambda: alive(pid))
    return pid, url


def _refused(answer: httpx.Response, code: str) -> None:
    assert answer.status_code == 503, answer.text
    assert answer.headers["retry-after"].isdigit()
    assert answer.json() == {"error": MESSAGES[code.removeprefix("storage_")], "code": code}


def test_a_full_disk_refuses_new_work_with_503_and_accepted_jobs_finish_after(
        small_disk: SmallDisk, tmp_path: Path) -> None:
    db, log = small_disk.where / "jobs.sqlite", tmp_path / "serve.log"
    _, url = _serve(small_disk, db, log)
    with httpx.Client(base_url=url, timeout=60) as c:
        accepted = []
        for seed in range(2):  # what the 3 MB disk holds with their files
            r = c.post("/v1/runs", json={"task": 8, "seed": seed})
            assert r.status_code == 202, r.text
            accepted.append(r.json()["id"])
        small_disk.fill()
        for seed in range(2, 12):
            _refused(c.post("/v1/runs", json={"task": 8, "seed": seed}), "storage_full")
        assert c.get("/v1/info").status_code == 200  # what is stored is still read
        time.sleep(3)  # the worker meets the full disk, and waits
        assert all(c.get(f"/v1/runs/{i}").json()["state"] in ("queued", "running", "done")
                   for i in accepted)
        small_disk.free()
        assert [wait_done(c, i)["state"] for i in accepted] == ["done", "done"]
    text = log.read_text()
    assert "Traceback" not in text, text[-3000:]
    # Once for new work, once per worker and supervisor at most; not once per try.
    assert 1 <= text.count("the disk holding the jobs is full") <= 3, text[-3000:]


#: Two runs queued in a database (the first argument), their ids written to the second.
QUEUE_TWO_RUNS = """
import json, sys
from pathlib import Path
from llm_grop.service.jobs import JobStore
store = JobStore(Path(sys.argv[1]))
ids = [store.submit("run", {"task": 8, "seed": seed}, "127.0.0.1", queue=10)
       for seed in range(2)]
store.close()
Path(sys.argv[2]).write_text(json.dumps(ids))
"""


def test_a_read_only_database_refuses_new_work_and_queued_jobs_run_once_writable(
        small_disk: SmallDisk, tmp_path: Path) -> None:
    db, log = small_disk.where / "jobs.sqlite", tmp_path / "serve.log"
    ids = tmp_path / "queued.json"
    made = small_disk.run([sys.executable, "-c", QUEUE_TWO_RUNS, str(db), str(ids)], log,
                          server_env())
    assert made == 0, log.read_text()
    queued = json.loads(ids.read_text())
    small_disk.read_only(db)
    _, url = _serve(small_disk, db, log)
    with httpx.Client(base_url=url, timeout=60) as c:
        _refused(c.post("/v1/runs", json={"task": 8, "seed": 5}), "storage_read_only")
        time.sleep(2)  # the worker tries to claim a job, and waits
        assert [c.get(f"/v1/runs/{i}").json()["state"] for i in queued] == ["queued"] * 2
        small_disk.writable(db)
        assert [wait_done(c, i)["state"] for i in queued] == ["done", "done"]
        again = c.post("/v1/runs", json={"task": 8, "seed": 6})
        assert again.status_code == 202, again.text
    text = log.read_text()
    assert "Traceback" not in text, text[-3000:]
    assert 1 <= text.count("the disk holding the jobs is read-only") <= 3, text[-3000:]
