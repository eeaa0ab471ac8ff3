"""The ``ray`` executor: each trial a Ray task, on a local or a remote Ray cluster.

Needs the ``ray`` extra (``pip install 'llm-grop[ray]'``). Without ``--ray-address`` (and
without ``$RAY_ADDRESS``) it starts a Ray cluster on this machine with ``--workers`` CPUs
(every CPU by default) and stops it at the end; with one it joins that cluster and leaves
it running; a watchdog process (:mod:`.ray_watchdog`) stops the cluster it started should
this process be killed. A cluster it starts runs its nodes on 127.0.0.1, and a cluster at a
loopback address (``127.0.0.1:PORT``) is joined with the driver on that address
(:mod:`.ray_loopback`): nothing it starts or joins on this machine uses the machine's
network address. Every node must have llm-grop installed, with the same version and
plugins as the driver, and must reach the files the experiment names (a scene, a replay
recording, catalogs, tasks) at the same paths.

* **Tasks.** A task runs a batch of up to :data:`MAX_BATCH` trials one after another and
  streams each one's result back as it ends (a Ray streaming generator), so a worker waits
  for Ray's scheduler once a batch, and the driver still writes each trial when it ends.
  A task reserves ``cpus_per_trial`` CPUs (fractions let trials that wait on a remote LLM
  share a CPU). Each Ray worker process keeps its trial runners
  (:class:`~llm_grop.experiment.worker.Runners`), so a model loads once per worker, not
  once per trial. At most ``workers`` tasks run at once (by default the cluster's CPUs over
  ``cpus_per_trial``, each with a batch queued behind it), so a sweep of a million trials
  never queues a million.
* **Pictures** travel back to the driver with the task's result and the driver writes them
  into the results directory: the nodes need no shared file system.
* **Results.** The driver alone appends to ``trials.jsonl``. On Ctrl-C or an error it
  cancels the tasks still in flight; a rerun resumes as after a local run.
* **Lost nodes.** A batch whose worker process or node dies is run again on the nodes
  left, up to :data:`TASK_RETRIES` times. Ray replays the whole batch and drops the
  results the driver already has, so the trials it had streamed back run again (the LLM
  cache answers their calls) but every row is written once. An error in a trial itself
  is not retried.
* **The LLM cache** is a directory on each node (``--cache-dir``); nodes that share it over
  a network file system share answers too.
* **Signals.** Ctrl-C and SIGTERM stop a Ray bench as they stop a local one (the driver's
  handlers stay this process's): ``ray.init`` replaces the SIGTERM handler with one that
  exits with status 15, so the handler it found is put back, and a SIGTERM Ray takes while
  it starts is handed to it; Ray's native failure signal handler, which prints a stack
  dump on SIGTERM and aborts 3 s later, is left out (``RAY_DISABLE_FAILURE_SIGNAL_HANDLER``,
  set unless already set, before Ray is imported; the cluster this driver starts inherits
  it).
"""

from __future__ import annotations

import logging
import math
import os
import signal
import socket
import subprocess
import sys
import threading
from collections import deque
from collections.abc import Generator, Iterator, Sequence
from typing import Any

from llm_grop import plugins
from llm_grop.errors import BadInput, LLMGropError
from llm_grop.experiment.executors import ExecutorOptions, Registered
from llm_grop.experiment.ray_loopback import node_address, use_loopback
from llm_grop.experiment.worker import Done, Job, Runners, run_job

log = logging.getLogger(__name__)

#: Times a batch lost to a dead worker or node is run again before the bench stops.
TASK_RETRIES = 3
#: Batches in flight per task slot, so a worker never waits for the driver to hand it work.
_IN_FLIGHT_PER_SLOT = 2
#: Trials one task runs at most, one after another, streaming each one's result back as it
#: ends: a worker waits for Ray's scheduler once a batch rather than once a trial.
MAX_BATCH = 8

# Each Ray worker process keeps its own runners.
_RUNNERS = Runners()


def _trials(jobs: list[Job], registered: Registered) -> Iterator[Done]:
    """A Ray task (a streaming generator): each trial of ``jobs`` in turn, its pictures
    shipped back, yielded as it ends."""
    plugins.restore(registered)  # cheap, and a worker may serve several drivers
    for job in jobs:
        yield run_job(job, _RUNNERS, ship_pictures=True)


class RayExecutor:
    """Runs trials as Ray tasks, a batch each (see the module's documentation)."""

    name = "ray"
    spawns = True

    def __init__(self, options: ExecutorOptions) -> None:
        # Read once, when Ray is first imported; a user's own setting is kept.
        os.environ.setdefault("RAY_DISABLE_FAILURE_SIGNAL_HANDLER", "1")
        # On loopback for a cluster it starts or joins there: Ray would start the one on
        # this machine's network address, and dial the other there. Joining, the driver
        # takes the address of the cluster's node that Ray finds on this machine (its
        # raylet): 127.0.0.1 for a cluster on loopback.
        if node_address(options.address if options.address is not None
                        else os.environ.get("RAY_ADDRESS")) is not None:
            use_loopback()
        try:
            import ray
        except ImportError:
            raise BadInput("Ray is not installed; install it with pip install "
                           "'llm-grop[ray]'", param="executor", value="ray") from None
        if options.cpus_per_trial <= 0:
            raise BadInput(f"must be above 0, got {options.cpus_per_trial:g}",
                           param="cpus_per_trial")
        self._ray = ray
        self.options = options
        self.workers = options.workers
        self._watchdog: subprocess.Popen[bytes] | None = None

    def run(self, jobs: Sequence[Job], registered: Registered) -> Generator[Done, None, None]:
        """Every job's :class:`Done`, in the order they finish."""
        if not jobs:
            return
        ray = self._ray
        started = self._connect()
        streams: dict[Any, deque[Job]] = {}
        try:
            # A batch lost with its worker or node is run again elsewhere (trials are
            # deterministic, and only this driver writes, so each row still comes once);
            # a trial's own error is not retried.
            remote = ray.remote(num_cpus=self.options.cpus_per_trial,
                                max_retries=TASK_RETRIES, retry_exceptions=False,
                                num_returns="streaming")(_trials)
            # --workers caps the batches, so the trials, running at once; without it the
            # cluster's slots are kept busy, with a batch queued behind each.
            window = self.options.workers or _IN_FLIGHT_PER_SLOT * max(
                1, int(ray.cluster_resources().get("CPU", 1) / self.options.cpus_per_trial))
            shared = ray.put(dict(registered))
            queue = deque(jobs)
            while True:
                while len(streams) < window and queue:
                    # Batches shrink as the queue does, so that no worker ends long after
                    # the others.
                    size = max(1, min(MAX_BATCH, len(queue) // (2 * window)))
                    batch = [queue.popleft() for _ in range(size)]
                    streams[remote.remote(batch, shared)] = deque(batch)
                if not streams:
                    break
                ready, _ = ray.wait(list(streams), num_returns=1)
                failed: Exception | None = None
                for stream in ready:
                    waiting = streams[stream]
                    try:
                        ref = next(stream)
                    except StopIteration:
                        # Ray reports a failed batch as an error in its stream, never so.
                        spec = waiting[0].spec
                        raise LLMGropError(f"task {spec.task} trial {spec.trial} "
                                           f"{spec.method}: its Ray task ended without a "
                                           "result") from None
                    job = waiting.popleft()
                    if not waiting:
                        del streams[stream]
                    try:
                        done = self._result(ref, job)
                    except Exception as exc:  # noqa: BLE001 - raised once the others are in
                        failed = failed or exc
                        continue
                    yield done
                if failed is not None:
                    raise failed
        finally:
            for stream in streams:
                ray.cancel(stream, force=True)
            if started:
                try:
                    ray.shutdown()
                finally:
                    self._stop_watchdog()

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
                check_joinable(address)
                _init(ray, address=address, **kwargs)
            else:
                workers = self.options.workers
                cpus = None if workers is None else math.ceil(
                    workers * self.options.cpus_per_trial)
                # Should this process be killed, even while Ray starts, nothing it started
                # must outlive it.
                self._watchdog = subprocess.Popen(
                    [sys.executable, "-m", "llm_grop.experiment.ray_watchdog",
                     str(os.getpid())], start_new_session=True, stdin=subprocess.DEVNULL,
                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                try:
                    _init(ray, num_cpus=cpus, **kwargs)
                except Exception:
                    # Ray said no and cleaned up. An interrupt instead leaves the watchdog
                    # to take down what Ray had started when it was cut off, which Ray's
                    # own shutdown cannot reach, once this process ends.
                    self._stop_watchdog()
                    raise
        except (ConnectionError, RuntimeError, ValueError) as exc:
            where = f"the Ray cluster at {address}" if address else "a local Ray cluster"
            raise BadInput(f"cannot reach {where}: {' '.join(str(exc).split())[:200]}",
                           param="executor", value="ray") from None
        return True

    def _stop_watchdog(self) -> None:
        """End the watchdog of the cluster this executor started, if it runs one."""
        if self._watchdog is not None:
            self._watchdog.kill()
            self._watchdog.wait()
            self._watchdog = None

    def _result(self, ref: Any, job: Job) -> Done:
        """The task's :class:`Done`. A failure is one line naming the trial: llm-grop's own
        errors as they are, a worker that could not import or read what the trial needs
        as bad input, a worker or node that died likewise; anything else is raised as the
        task raised it."""
        ray = self._ray
        spec = job.spec
        where = f"task {spec.task} trial {spec.trial} {spec.method}"
        try:
            done: Done = ray.get(ref)
        except ray.exceptions.RayError as exc:
            # A task's own exception is its cause; a system error (its arguments could not
            # be read: a module the node lacks) has none.
            cause = getattr(exc, "cause", None)
            if isinstance(cause, LLMGropError):
                raise cause from None
            system = ray.exceptions.RaySystemError
            setup = isinstance(cause, ImportError | OSError | system) or (
                cause is None and isinstance(exc, system))
            if setup:
                raise BadInput(f"{where}: a Ray worker could not run it: "
                               f"{_line(cause or exc)} (every node needs llm-grop, its "
                               "plugins and the experiment's files)") from None
            if isinstance(cause, Exception):
                raise cause from None
            raise LLMGropError(f"{where}: the Ray worker running it failed: "
                               f"{_line(exc)}") from None
        return done


def _init(ray: Any, **kwargs: Any) -> None:
    """``ray.init(**kwargs)``, this process's SIGTERM handler kept.

    In the main thread ``ray.init`` first installs a SIGTERM handler that exits with
    status 15 (``sys.exit``), and leaves it there. The handler it found is put back
    afterwards, and a SIGTERM that reached Ray's while it started is sent again, to it.
    """
    if threading.current_thread() is not threading.main_thread():
        ray.init(**kwargs)  # Ray leaves the signal handlers be outside the main thread
        return
    ours = signal.getsignal(signal.SIGTERM)
    if ours is None:  # a handler set outside Python, which could not be put back
        ray.init(**kwargs)
        return
    try:
        try:
            ray.init(**kwargs)
        finally:
            signal.signal(signal.SIGTERM, ours)
    except SystemExit as exc:
        if exc.code != signal.SIGTERM:
            raise
        # Again: the signal may have come just before the handler was put back.
        signal.signal(signal.SIGTERM, ours)
        signal.raise_signal(signal.SIGTERM)
        raise  # the handler ignored it (SIG_IGN); Ray's start was cut off all the same


def _line(exc: BaseException) -> str:
    """``Type: the first line of the message``, at most 200 characters."""
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}"[:200]


#: Seconds to wait for a Ray cluster's port before calling it unreachable.
_PROBE_S = 5.0
#: Seconds a trial join of a Ray cluster may take before it is called unjoinable.
JOIN_S = 60.0
_JOIN = ("import sys, ray; ray.init(address=sys.argv[1], include_dashboard=False, "
         "log_to_driver=False, configure_logging=False); ray.shutdown()")


def check_joinable(address: str) -> None:
    """:class:`ConnectionError` unless a throwaway process joins the cluster at
    ``address`` within :data:`JOIN_S` seconds, as the driver will (it inherits the
    driver's environment, Ray's loopback switch included): a port that answers is not yet
    a cluster this machine can join (one bound to another host's loopback accepts the
    connection, and Ray then waits for minutes)."""
    try:
        probe = subprocess.run([sys.executable, "-c", _JOIN, address], capture_output=True,
                               text=True, timeout=JOIN_S)
    except subprocess.TimeoutExpired:
        raise ConnectionError(f"could not join it within {JOIN_S:g} s (is the cluster's "
                              "node address reachable from here?)") from None
    if probe.returncode != 0:
        lines = [line for line in probe.stderr.strip().splitlines() if line.strip()]
        raise ConnectionError(lines[-1] if lines else f"exit status {probe.returncode}")


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
