"""Flags that say where trials run and how LLM answers are cached, and what they build."""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import Any

import click

from llm_grop.cli.options import F, check_out_dir
from llm_grop.cli.settings import option
from llm_grop.errors import BadInput

log = logging.getLogger(__name__)


#: ``--no-cache``, beside the ``cache`` setting's ``--cache-dir``.
NO_CACHE = click.option("--no-cache", is_flag=True,
                        help="Ask the LLM every call, without the shared answer cache.")

_EXECUTION_OPTIONS = [
    click.option("--executor", default="local", show_default=True,
                 help="Where trials run: local (processes on this machine) or ray (Ray "
                      "tasks; needs `pip install 'llm-grop[ray]'`)."),
    click.option("--workers", type=click.IntRange(1),
                 help="Trials at once: local processes, or Ray tasks in flight [default: 1 "
                      "locally; under Ray the cluster's CPUs over --cpus-per-trial]."),
    click.option("--ray-address", metavar="ADDR",
                 help="The Ray cluster to join, e.g. ray://head:10001, auto, or "
                      "127.0.0.1:6379 (a cluster on loopback, joined there) [default: "
                      "$RAY_ADDRESS, else a cluster started on this machine, on 127.0.0.1]."),
    click.option("--cpus-per-trial", default=1.0, show_default=True,
                 type=click.FloatRange(0, min_open=True),
                 help="CPUs a Ray task reserves; below 1 lets trials that wait on a remote "
                      "LLM share a CPU."),
    click.option("--llm-threads", type=click.IntRange(1),
                 help="The embedded model's CPU threads in each worker [default: the cores "
                      "over --workers locally, 1 under Ray]."),
    option("cache"),
    NO_CACHE,
    click.option("--max-failed", type=click.IntRange(1),
                 help="Stop once this many trials got no usable LLM answer after their retries "
                      "(the server is down) [default: never; such trials are recorded "
                      "llm-failed, and a rerun retries them]."),
]


def cache_setting(cache_dir: str | Path | None, no_cache: bool, *, as_written: bool = False
                  ) -> str | None:
    """The LLM cache's directory from the flags of ``--cache-dir`` and ``--no-cache`` (``None``: no
    cache). The default is left as written (``~``, ``$LLM_GROP_CACHE_DIR``) with
    ``as_written``, so that each node of a cluster finds its own home's cache; a default
    that cannot be written is a warning and no cache, a given one bad input."""
    from llm_grop.llm.cache import DEFAULT_DIR, ENV_DIR, default_dir

    if no_cache:
        return None
    if cache_dir is not None:
        cache_dir = Path(cache_dir)
        check_out_dir("cache_dir", cache_dir)
        return str(cache_dir.expanduser().absolute())
    try:
        check_out_dir("cache_dir", default_dir())
    except BadInput as exc:
        log.warning("no LLM cache: the default %s", str(exc).removeprefix("--cache-dir "))
        return None
    if as_written:
        return os.environ.get(ENV_DIR) or str(DEFAULT_DIR)
    return str(default_dir())


def execution_flags(f: F) -> F:
    """Add the flags that say where trials run and how LLM answers are cached."""
    for one in reversed(_EXECUTION_OPTIONS):
        f = one(f)
    return f


def execution_settings(executor: str, workers: int | None, ray_address: str | None,
                       cpus_per_trial: float, llm_threads: int | None, cache: Path | None,
                       no_cache: bool, **_: Any) -> tuple[Any, int, str | None]:
    """``(executor, embedded model threads, LLM cache directory or None)`` from the flags
    of :func:`execution_flags`; the executor is built (Ray is imported) only for ``ray``."""
    from llm_grop.experiment.executors import (
        EXECUTORS,
        ExecutorOptions,
        create_executor,
        default_threads,
    )

    name = EXECUTORS.key(executor)
    if ray_address is not None and name != "ray":
        raise BadInput("--ray-address: only with --executor ray")
    made = create_executor(name, ExecutorOptions(workers=workers, address=ray_address,
                                                 cpus_per_trial=cpus_per_trial))
    threads = llm_threads or default_threads(name, workers)
    return made, threads, cache_setting(cache, no_cache, as_written=True)
