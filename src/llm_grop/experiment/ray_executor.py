"""The ``ray`` executor: each trial a Ray task, on a local or a remote Ray cluster.

Needs the ``ray`` extra (``pip install 'llm-grop[ray]'``). Without ``--ray-address`` (and
without ``$RAY_ADDRESS``) it starts a Ray cluster on this machine with ``--workers`` CPUs
(every CPU by default) and stops it at the end; with one it joins that cluster and leaves
it running. Every node must have llm-grop installed, with the same version and plugins as
the driver, and must reach the files the experiment names (a scene, a replay recording,
catalogs, tasks) at the same paths.

* **Tasks.** A task runs one trial and reserves ``cpus_per_trial`` CPUs (fractions let
  trials that wait on a remote LLM share a CPU). Each Ray worker process keeps its trial
  runners (:class:`~llm_grop.experiment.worker.Runners`), so a model loads once per worker,
  not once per trial. At most ``workers`` tasks are in flight (the cluster's CPUs over
  ``cpus_per_trial`` by default), so a sweep of a million trials never queues a million.
* **Pictures** travel back to the driver with the task's result and the driver writes them
  into the results directory: the nodes need no shared file system.
* **Results.** The driver alone appends to ``trials.jsonl``. On Ctrl-C or an error it
  cancels the tasks still in flight; a rerun resumes as after a local run.
* **The LLM cache** is a directory on each node (``--cache-dir``); nodes that share it over
  a network file system share answers too.
"""

from __future__ import annotations

import logging
import math
import socket
from collections.abc import Iterator, Sequence
from typing import Any

from llm_grop import plugins
from llm_grop.errors import BadInput, LLMGropError
from llm_grop.experiment.executors import ExecutorOptions, Registered
from llm_grop.experiment.worker import Done, Job, Runners, run_job

log = logging.getLogger(__name__)

#: Tasks in flight per task slot, so a worker never waits for the driver to hand it work.
_IN_FLIGHT_PER_SLOT = 2

# Each Ray worker process keeps its own runners.
_RUNNERS = Runners()


def _trial(job: Job, registered: Registered) -> Done:
    """A Ray task: one trial, its pictures shipped back."""
    plugins.restore(registered)  # cheap, and a worker may serve several drivers
    return run_job(job, _RUNNERS, ship_pictures=True)


class RayExecutor:
    """Runs each trial as a Ray task (see the module's documentation)."""

    name = "ray"
    spawns = True

    def __init__(self, options: ExecutorOptions) -> None:
        try:
            import ray
        except ImportError:
            raise BadInput("--executor ray: Ray is not installed; install it with "
                           "pip install 'llm-grop[ray]'") from None
        if options.cpus_per_trial <= 0:
            raise BadInput(f"--cpus-per-trial: must be above 0, got {options.cpus_per_trial:g}")
        self._ray = ray
        self.options = options
        self.workers = options.workers

    def run(self, jobs: Sequence[Job], registered: Registered) -> Iterator[Done]:
        """Every job's :class:`Done`, in the order they finish."""
        if not jobs:
            return
        ray = self._ray
        started = self._connect()
        pending: dict[Any, Job] = {}
        try:
            remote = ray.remote(num_cpus=self.options.cpus_per_trial, max_retries=0)(_trial)
            slots = self.options.workers or max(
                1, int(ray.cluster_resources().get("CPU", 1) / self.options.cpus_per_trial))
            window = slots * _IN_FLIGHT_PER_SLOT
            shared = ray.put(dict(registered))
            queue = iter(jobs)
            while True:
                while len(pending) < window and (job := next(queue, None)) is not None:
                    pending[remote.remote(job, shared)] = job
                if not pending:
                    break
                waiting = list(pending)
                ready, rest = ray.wait(waiting, num_returns=1)
                if rest:  # whatever else has finished meanwhile, without waiting
                    ready += ray.wait(rest, num_returns=len(rest), timeout=0)[0]
                for ref in ready:
                    del pending[ref]
                    yield self._result(ref)
        finally:
            for ref in pending:
                ray.cancel(ref, force=True)
            if started:
                ray.shutdown()

    def _connect(self) -> bool:
        """Join or start a cluster; ``True`` when this call started it (and must stop it)."""
        ray = self._ray
        if ray.is_initialized():
            return False
        kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": True,
                                  "logging_level": logging.WARNING, "configure_logging": False}
        address = self.options.address
        if not log.isEnabledFor(logging.DEBUG):
            # Ray's start-up notes would interleave with the progress bar; errors still show.
            logging.getLogger("ray").setLevel(logging.ERROR)
        try:
            if address is not None:
                _check_reachable(address)
                ray.init(address=address, **kwargs)
            else:
                workers = self.options.workers
                cpus = None if workers is None else math.ceil(
                    workers * self.options.cpus_per_trial)
                ray.init(num_cpus=cpus, **kwargs)
        except (ConnectionError, RuntimeError, ValueError) as exc:
            where = f"the Ray cluster at {address}" if address else "a local Ray cluster"
            raise BadInput(f"--executor ray: cannot reach {where}: "
                           f"{' '.join(str(exc).split())[:200]}") from None
        return True

    def _result(self, ref: Any) -> Done:
        """The task's :class:`Done`; llm-grop's own errors in a task are raised as they
        are, so the command prints their one line."""
        ray = self._ray
        try:
            done: Done = ray.get(ref)
        except ray.exceptions.RayTaskError as exc:
            cause = getattr(exc, "cause", None)
            if isinstance(cause, LLMGropError):
                raise cause from None
            raise
        return done


#: Seconds to wait for a Ray cluster's port before calling it unreachable.
_PROBE_S = 5.0


def _check_reachable(address: str) -> None:
    """:class:`ConnectionError` unless ``address`` (``host:port`` or ``ray://host:port``;
    ``auto`` and other forms are left to Ray) accepts a connection: Ray itself retries an
    unreachable address for minutes."""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not port.isdigit():
        return
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=_PROBE_S).close()
    except OSError as exc:
        raise ConnectionError(f"nothing answers at {host}:{port} "
                              f"({exc.strerror or exc})") from None
