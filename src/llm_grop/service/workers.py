"""The bounded pool of worker processes that run the service's jobs, and its supervisor.

Each worker claims the next queued job from the database, runs it (:mod:`.tasks`) and
records its result under its claim. The supervisor, a thread in the server, restarts a
worker that died (its job is queued again, up to a bound), stops one whose job ran over
its time or was cancelled, and ends that job. A worker dies with the server: the kernel
kills it when its parent goes (``PR_SET_PDEATHSIG``), and it checks its parent between
jobs where that is not available.

While the disk under the database refuses writes (full, read-only: :mod:`.storage`), a
worker claims nothing and holds the outcome of the job it ran until it can be recorded,
and the supervisor skips its writes; both wait with a bounded backoff and log the episode
once. A job whose own files could not be written is queued again (the attempt counts).
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import signal
import sqlite3
import threading
import time
from collections.abc import Callable
from functools import partial
from multiprocessing.process import BaseProcess
from pathlib import Path

from llm_grop.errors import BadInput, Infeasible, LLMError, LLMGropError, LLMTransient
from llm_grop.processes import ctrl_c_ignored_by_children, die_with_parent
from llm_grop.service.config import ServiceConfig
from llm_grop.service.jobs import Job, JobStore
from llm_grop.service.storage import Backoff, problem, state
from llm_grop.settings import in_words

log = logging.getLogger(__name__)

#: Seconds an idle worker waits between looks at the queue, at most.
IDLE_POLL_S = 0.05
#: Seconds between the supervisor's rounds.
SUPERVISE_S = 0.25
#: Seconds between the supervisor's prunings of ended jobs (``ServiceConfig.keep_s``).
PRUNE_S = 3600.0


def status_of(exc: BaseException) -> tuple[int, str]:
    """The HTTP status and one-line message a job's failure is answered with: the same
    wording and meaning as the CLI's exit codes (bad input 422, nothing feasible 409).

    The LLM's failures, configured wrong or not answering this time, are the server's
    (503): their words name the server's model files, endpoints and replay files, which
    stay in its log; so do an internal error's."""
    if isinstance(exc, Infeasible):
        return 409, str(exc)
    if isinstance(exc, LLMError | LLMTransient):
        return 503, "llm: the server's LLM backend could not answer this request; its log " \
                    "says why"
    if isinstance(exc, BadInput):
        return 422, in_words(exc, "json")
    if isinstance(exc, LLMGropError):
        return 422, str(exc)
    return 500, f"internal error: {type(exc).__name__} (the server's log has the details)"


def worker_main(config: ServiceConfig, parent: int) -> None:
    """A worker's life: claim, run, record, until its parent goes."""
    from llm_grop.service.tasks import Backends, perform

    die_with_parent()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the server stops its workers itself
    os.environ.setdefault("MUJOCO_GL", "osmesa")
    store = JobStore(config.db)
    llms = Backends(config)
    backoff = Backoff(f"worker {os.getpid()}", log)
    where = config.db.parent
    idle = 0.005
    try:
        while os.getppid() == parent:
            try:
                refused = state(where)
                job = None if refused else store.claim(os.getpid())
            except (sqlite3.Error, OSError) as exc:
                refused = problem(exc, where)
                if refused is None:
                    raise
            if refused is not None:
                time.sleep(backoff.wait_s(refused))
                continue
            if job is None:
                time.sleep(idle)
                idle = min(idle * 2, IDLE_POLL_S)
                continue
            backoff.cleared()  # the claim was written
            idle = 0.005
            _run_one(store, job, config, llms, perform, backoff)
    finally:
        llms.close()
        store.close()


def _run_one(store: JobStore, job: Job, config: ServiceConfig, llms: object,
             perform: object, backoff: Backoff) -> None:
    where = config.db.parent

    def progress(message: str) -> None:
        try:
            store.event(job, message)
        except (sqlite3.Error, OSError) as exc:
            # A progress line is not worth the job: it is left out while the disk is full.
            refused = problem(exc, where)
            if refused is None:
                raise
            backoff.trouble(refused)

    record: Callable[[], object]
    try:
        result, files = perform(job.kind, job.body, config, llms,  # type: ignore[operator]
                                progress)
        record = partial(store.finish, job, result, files)
    except Exception as exc:  # noqa: BLE001 - every failure ends the job with its reason
        refused = problem(exc, where)
        if refused is not None:
            backoff.trouble(refused)
            record = partial(store.orphaned, job, "its files could not be written (the "
                             f"server's disk was {refused.replace('_', '-')})", status=503)
        else:
            status, message = status_of(exc)
            if status >= 500:
                log.error("job %s failed: %s: %s", job.id, type(exc).__name__, exc,
                          exc_info=status == 500)
            record = partial(store.fail, job, status, message)
    _record(record, backoff, where)


def _record(write: Callable[[], object], backoff: Backoff, where: Path) -> None:
    """``write`` a job's outcome, trying again while the disk refuses it (a worker whose
    job ran over its time is stopped by the supervisor meanwhile)."""
    while True:
        try:
            write()
        except (sqlite3.Error, OSError) as exc:
            refused = problem(exc, where)
            if refused is None:
                raise
            time.sleep(backoff.wait_s(refused))
            continue
        backoff.cleared()
        return


class WorkerPool:
    """``config.workers`` worker processes and the supervisor thread that keeps them."""

    def __init__(self, config: ServiceConfig) -> None:
        self.config = config
        self._ctx = multiprocessing.get_context("spawn")
        self._procs: list[BaseProcess] = []
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._store: JobStore | None = None
        self._next_prune = 0.0  # time.monotonic()

    def start(self) -> None:
        """Start the workers and the supervisor."""
        self._store = JobStore(self.config.db)
        self._procs = [self._spawn() for _ in range(self.config.workers)]
        self._thread = threading.Thread(target=self._supervise, name="llm-grop-supervisor",
                                        daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop the supervisor and every worker (their jobs are recovered at the next
        start)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
        for p in self._procs:
            p.kill()
        for p in self._procs:
            p.join(timeout=5)
        if self._store is not None:
            self._store.close()

    def pids(self) -> list[int]:
        """The workers' process ids."""
        return [p.pid for p in self._procs if p.pid is not None]

    def _spawn(self) -> BaseProcess:
        p = self._ctx.Process(target=worker_main, args=(self.config, os.getpid()),
                              name="llm-grop-worker", daemon=True)
        with ctrl_c_ignored_by_children():
            p.start()
        return p

    def _supervise(self) -> None:
        backoff = Backoff("supervisor", log)
        wait = SUPERVISE_S
        while not self._stop.wait(wait):
            wait = SUPERVISE_S
            try:
                self._round()
            except Exception as exc:  # noqa: BLE001 - the supervisor must outlive one bad round
                refused = problem(exc, self.config.db.parent)
                if refused is None:
                    log.exception("supervisor round failed")
                else:
                    wait = max(wait, backoff.wait_s(refused))
                continue
            if state(self.config.db.parent) is None:  # a round may have written nothing
                backoff.cleared()

    def _round(self) -> None:
        store = self._store
        assert store is not None
        now = time.time()
        for p in self._procs:
            held = [j for j in store.running() if j.worker == p.pid]
            stop = [j for j in held if j.cancel or (
                j.started is not None and now - j.started > self.config.limits.run_time_s)]
            if not stop:
                continue
            p.kill()
            p.join(timeout=5)
            for job in stop:
                if job.cancel:
                    store.end(job, "cancelled", None, "cancelled by the client")
                else:
                    store.end(job, "failed", 504, f"ran longer than this server's "
                                                  f"{self.config.limits.run_time_s:g} s")
        for k, p in enumerate(self._procs):
            if not p.is_alive():
                p.join(timeout=1)
                self._procs[k] = self._spawn()
        # Whatever a dead worker held (it was killed for another job, it crashed, or its
        # job was claimed just before the kill) goes back to the queue.
        live = {p.pid for p in self._procs if p.is_alive()}
        for job in store.running():
            if job.worker not in live:
                store.orphaned(job, "its worker died")
        if self.config.keep_s is not None and time.monotonic() >= self._next_prune:
            gone = store.prune(now - self.config.keep_s)
            self._next_prune = time.monotonic() + PRUNE_S  # a failed prune is tried again
            if gone:
                log.info("pruned %d job(s) that ended over %g days ago", gone,
                         self.config.keep_s / 86400)
