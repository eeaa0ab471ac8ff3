"""Where a bench's trials run: the :class:`Executor` protocol, its registry and ``local``.

The driver (:mod:`llm_grop.experiment.runner`) hands an executor every pending
:class:`~llm_grop.experiment.worker.Job` and takes the finished ones back, in any order, as
they end; it alone writes results. An executor never writes a results file, so resume and
Ctrl-C behave the same whichever one runs the trials.

============ ============================================================= ===============
executor     where trials run                                              needs
============ ============================================================= ===============
``local``    ``--workers`` processes on this machine (in this process for  nothing
             one worker)
``ray``      Ray tasks on a local or remote Ray cluster                    the ``ray``
             (:mod:`llm_grop.experiment.ray_executor`)                     extra
============ ============================================================= ===============

Entry point group ``llm_grop.executors``: a factory ``(ExecutorOptions) -> Executor``.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import signal
from collections.abc import Generator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

from llm_grop import plugins
from llm_grop.experiment.worker import Done, Job, Runners, run_job
from llm_grop.plugins import Registry
from llm_grop.processes import ctrl_c_ignored_by_children, die_with_parent

log = logging.getLogger(__name__)

#: Run-time plugin entries as :func:`llm_grop.plugins.registered` collects them.
Registered = Mapping[str, tuple[str, Mapping[str, Any]]]


@dataclass(frozen=True)
class ExecutorOptions:
    """How to run trials.

    ``workers``: trials at once (``None``: 1 locally; under Ray, the cluster's CPUs over
    ``cpus_per_trial``). ``address``: the Ray cluster to join (``None``: start one on this
    machine, or join ``$RAY_ADDRESS``). ``cpus_per_trial``: CPUs a Ray task reserves
    (fractions let trials that wait on a remote LLM share a CPU).
    """

    workers: int | None = None
    address: str | None = None
    cpus_per_trial: float = 1.0


@runtime_checkable
class Executor(Protocol):
    """Runs jobs and yields each one's :class:`Done` as it finishes.

    ``run`` may be left unfinished (the driver stops iterating on Ctrl-C or an error):
    closing the iterator stops the work still under way. ``registered`` holds the plugin
    entries registered at run time that workers must register again; ``spawns`` says
    whether jobs run in other processes (which need them), and ``workers`` how many
    jobs it runs at once (``None``: as many as its cluster allows).
    """

    name: str
    spawns: bool
    workers: int | None

    def run(self, jobs: Sequence[Job], registered: Registered) -> Generator[Done, None, None]: ...


# Each pool worker process keeps its own runners; a failure to start is reported with its
# first job, because a pool restarts a worker whose initializer raises, forever.
_RUNNERS = Runners()
_START_ERROR: Exception | None = None


def _init_worker(registered: Registered, log_level: int) -> None:
    global _START_ERROR
    logging.basicConfig(format="llm-grop: worker %(process)d: %(levelname)s: %(name)s: "
                        "%(message)s")
    logging.getLogger("llm_grop").setLevel(log_level)
    # The driver handles Ctrl-C and stops the workers; they must not die mid-row, nor
    # outlive a driver that was killed.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent()
    try:
        plugins.restore(registered)
    except Exception as exc:  # noqa: BLE001 - handed to the driver with the first job
        _START_ERROR = exc


def _work(job: Job) -> Done:
    if _START_ERROR is not None:
        raise _START_ERROR
    return run_job(job, _RUNNERS)


class LocalExecutor:
    """``workers`` processes on this machine (spawned, so each loads its own model), or
    this process alone for one worker."""

    name = "local"

    def __init__(self, options: ExecutorOptions) -> None:
        self.workers = options.workers or 1
        self.spawns = self.workers > 1

    def run(self, jobs: Sequence[Job], registered: Registered) -> Generator[Done, None, None]:
        """Every job's :class:`Done`, in the order they finish."""
        if not jobs:
            return
        if self.workers <= 1:
            runners = Runners()
            for job in jobs:
                yield run_job(job, runners)
            return
        ctx = multiprocessing.get_context("spawn")
        with ctrl_c_ignored_by_children():
            pool = ctx.Pool(min(self.workers, len(jobs)), initializer=_init_worker,
                            initargs=(registered, log.getEffectiveLevel()))
        try:
            yield from pool.imap_unordered(_work, jobs, chunksize=1)
            pool.close()
        finally:
            pool.terminate()
            pool.join()


def describe(executor: Executor) -> str:
    """How ``executor`` runs trials, for a summary line: ``2 local workers``, ``ray``."""
    workers = executor.workers
    if executor.name == "local":
        return f"{workers} local worker{'s' if workers != 1 else ''}"
    return f"{executor.name}" + (f" ({workers} at once)" if workers else "")


def default_threads(executor: str, workers: int | None) -> int:
    """The embedded model's CPU threads per worker when ``--llm-threads`` is not given:
    one under Ray (each trial reserves one CPU), else this machine's cores shared out
    among the local workers."""
    if executor != "local":
        return 1
    return max(1, (os.cpu_count() or 1) // max(1, workers or 1))


EXECUTORS: Registry[Any] = Registry(
    group="llm_grop.executors", kind="executor", flag="--executor", module=__name__,
    builtins={"local": "llm_grop.experiment.executors:LocalExecutor",
              "ray": "llm_grop.experiment.ray_executor:RayExecutor"},
    factory="(ExecutorOptions) -> Executor", protocol=Executor,
    product=("name", "spawns", "workers", "run"))


def create_executor(name: str, options: ExecutorOptions | None = None) -> Executor:
    """Build the executor called ``name`` (Ray is imported only for ``ray``)."""
    executor: Executor = EXECUTORS.create(name, options or ExecutorOptions())
    return executor
