"""The paper's experiment (§IV): tasks x trials x methods, resumable, in parallel.

An output directory holds one experiment:

* ``experiment.json``: what makes results comparable (LLM, scene, chairs, sampler and
  planner settings, simulator, task and catalog files, version). A directory holding a different
  experiment is refused, so results are never mixed.
* ``trials.jsonl``: one :class:`~llm_grop.contract.models.TrialRow` per finished trial,
  appended and flushed as each one ends, so
  an interrupted run loses no finished trial. A rerun skips the trials already there.
  When every trial is done the file is rewritten in ``(task, trial, method)`` order
  (:mod:`llm_grop.experiment.rows` reads and writes it).
* ``images/``: each trial's final table, the requested objects listed at the top.
* ``.lock``: held by the run writing the directory (:mod:`llm_grop.locking`), so a second
  run on it is refused at once, naming the first's process id.
* ``summary.json``, ``summary.md`` and the paper's plots, ``fig3_rating_vs_time.png`` and
  ``fig5_rating_per_task.png``, made from every row.

Trial ``k`` of every task uses seed ``seed + k`` for every method, so methods see the same
scenes and chairs and the comparison is paired.

Trials run on an executor (:mod:`llm_grop.experiment.executors`: local processes or
Ray); this process alone writes the results. Worker processes find installed plugins
themselves; methods, backends and simulators registered at run time are handed to them
(:func:`llm_grop.plugins.registered`). A sweep runs several experiments, each in its own
directory, through one executor (:func:`run_cells`).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from importlib import metadata, resources
from pathlib import Path
from typing import Any

from llm_grop import locking, plugins
from llm_grop.assembly import AUTO
from llm_grop.contract.models import TrialRow
from llm_grop.errors import BadInput, LLMTransient
from llm_grop.experiment.executors import Executor, ExecutorOptions, LocalExecutor
from llm_grop.experiment.paired import PairedComparison, paired_by_trial
from llm_grop.experiment.plots import plot_rating_per_task, plot_rating_vs_time
from llm_grop.experiment.rows import (
    ROWS,
    append_row,
    read_rows,
    rewrite_rows,
    row_key,
    sort_rows_file,
    table_order,
)
from llm_grop.experiment.summary import Summary, summarize, summary_markdown, summary_to_dict
from llm_grop.experiment.trial import TrialSettings, TrialSpec
from llm_grop.experiment.worker import Job
from llm_grop.files.jsonio import write_bytes, write_json, write_text
from llm_grop.llm.registry import BACKENDS
from llm_grop.methods.registry import METHODS
from llm_grop.simulation.registry import SIMULATORS

log = logging.getLogger(__name__)

#: The lock file one run holds in each results directory it writes (a sweep also in its
#: own directory, from start to its last report).
LOCK = ".lock"
#: Who holds a results directory's :data:`LOCK`, in a refused run's words.
HOLDER = "another llm-grop run on this directory"
IDENTITY = "experiment.json"


@dataclass(frozen=True)
class Experiment:
    """Which trials to run: ``tasks`` x ``trials`` x ``methods``, seeds from ``seed``."""

    tasks: tuple[int, ...]
    trials: int
    methods: tuple[str, ...]
    settings: TrialSettings
    seed: int = 0

    def specs(self) -> list[TrialSpec]:
        """Every trial, in ``(task, trial, method)`` order."""
        return [TrialSpec(m, t, k, self.seed + k) for t in self.tasks
                for k in range(self.trials) for m in self.methods]


@dataclass(frozen=True)
class Outcome:
    """What a run of :func:`run_experiment` did: every row in the directory, how many
    trials it ran now and skipped as done, and whether it was interrupted."""

    rows: tuple[TrialRow, ...]
    ran: int
    skipped: int
    interrupted: bool


def _digest(paths: Sequence[str | os.PathLike[str]]) -> str:
    h = hashlib.sha256()
    for p in paths:
        h.update(Path(p).read_bytes())
    return h.hexdigest()[:16]


def identity(exp: Experiment) -> dict[str, Any]:
    """The settings that decide a trial's result, named as the settings record's fields
    (:meth:`~llm_grop.settings.RunSettings.identity`), files by their contents' digests;
    equal identities may share a directory. Each trial sets its own method, task and seed
    (``seed`` is trial 0's)."""
    s = exp.settings.run
    tasks = resources.files("llm_grop").joinpath("data/tasks.yaml").read_bytes()
    catalog = resources.files("llm_grop").joinpath("data/catalog.yaml").read_bytes()
    doc = s.identity()
    for name in ("task", "method", "task_files", "catalog_files"):
        doc.pop(name)
    for name in ("replay", "preferences_file"):
        doc[name] = _digest([doc[name]]) if doc[name] else None
    return {
        "format": 2,
        "version": metadata.version("llm-grop"),
        **doc,
        "scene": _digest([s.scene]) if s.scene else "packaged",
        "seed": exp.seed,
        "plugins": _plugin_origins(exp),
        "tasks": hashlib.sha256(tasks).hexdigest()[:16] + (
            "+" + _digest(s.task_files) if s.task_files else ""),
        "catalog": hashlib.sha256(catalog).hexdigest()[:16] + (
            "+" + _digest(s.catalog_files) if s.catalog_files else ""),
    }


def _plugin_origins(exp: Experiment) -> dict[str, str]:
    """Where each component the experiment uses comes from, when llm-grop does not ship it
    (a plugin's version decides its results as llm-grop's own version does)."""
    llm = exp.settings.run.llm
    # ``auto`` is left so only when no method asks an LLM.
    used = [*([(BACKENDS, llm)] if llm != AUTO else []),
            (SIMULATORS, exp.settings.run.simulator), *((METHODS, m) for m in exp.methods)]
    origins = {f"{reg.kind} {name}": reg.origin(name) for reg, name in used}
    return {k: v for k, v in origins.items() if v != "llm-grop"}


def prepare_dir(out: Path, exp: Experiment) -> None:
    """Create ``out`` for ``exp``, or check it holds the same experiment."""
    mine = identity(exp)
    marker = out / IDENTITY
    if marker.exists():
        try:
            theirs = json.loads(marker.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            raise BadInput(f"{IDENTITY} is unreadable; choose another directory",
                           param="out", value=out) from None
        diff = sorted(k for k in mine.keys() | theirs.keys() if mine.get(k) != theirs.get(k))
        if diff:
            raise BadInput("holds another experiment's results (different "
                           f"{', '.join(diff)}); choose another directory", param="out",
                           value=out)
        return
    if out.exists() and any(out.iterdir()):
        raise BadInput(f"not empty and holds no {IDENTITY}; choose an empty or new "
                       "directory", param="out", value=out)
    out.mkdir(parents=True, exist_ok=True)
    write_json(marker, mine)


@dataclass(frozen=True)
class Cell:
    """One experiment and the directory that keeps its results (a bench runs one; a sweep
    one per combination of its grid)."""

    experiment: Experiment
    out: Path


def run_experiment(exp: Experiment, out: Path, *, workers: int = 1,
                   executor: Executor | None = None,
                   on_start: Callable[[int, int], None] | None = None,
                   on_row: Callable[[TrialRow], None] | None = None,
                   max_failed: int | None = None) -> Outcome:
    """Run the trials of ``exp`` not yet in ``out``; returns every row there.

    Trials run on ``executor`` (default: ``workers`` local processes).
    ``on_start(pending, skipped)`` is called once, ``on_row`` after each finished trial.
    """
    executor = executor or LocalExecutor(ExecutorOptions(workers=workers))
    (outcome,) = run_cells([Cell(exp, out)], executor, on_start=on_start,
                           on_row=None if on_row is None else lambda _, row: on_row(row),
                           max_failed=max_failed)
    return outcome


def run_cells(cells: Sequence[Cell], executor: Executor, *,
              on_start: Callable[[int, int], None] | None = None,
              on_row: Callable[[int, TrialRow], None] | None = None,
              keep_rows: bool = True, max_failed: int | None = None) -> tuple[Outcome, ...]:
    """Run every cell's trials not yet in its directory, all through one ``executor``, and
    return each cell's :class:`Outcome` (in ``cells``' order).

    Every directory is checked before any trial runs. This process alone writes results:
    a finished trial's pictures, then its row, appended and synced to its cell's
    ``trials.jsonl``; rows are not kept in memory while trials run, so a sweep of any size
    fits. ``on_start(pending, skipped)`` is called once with the totals over the cells;
    ``on_row(cell index, row)`` after each finished trial. Ctrl-C stops the executor and
    keeps every finished trial. Without ``keep_rows`` the outcomes hold no rows (read
    each cell's with :func:`read_rows`).

    A trial whose LLM failed (``status`` ``llm-failed``) counts as not done: a rerun runs
    it again and its new row replaces the old. With ``max_failed``, the run stops once
    that many trials of this run failed so: :class:`~llm_grop.errors.LLMTransient`,
    every finished trial kept.
    """
    used: dict[str, list[str]] = {BACKENDS.group: [], SIMULATORS.group: [], METHODS.group: []}
    for cell in cells:
        s = cell.experiment.settings.run
        used[BACKENDS.group].append(s.llm)
        used[SIMULATORS.group].append(s.simulator)
        used[METHODS.group] += cell.experiment.methods
    # Checked before any directory is made: an entry that cannot reach workers fails now.
    registered = plugins.registered(used) if executor.spawns else {}
    for cell in cells:
        # A directory in use (a sweep's own among them) is refused for that, naming who.
        locking.check(cell.out / LOCK, "out", cell.out, HOLDER)
        prepare_dir(cell.out, cell.experiment)
    held: list[int] = []
    try:
        for cell in cells:
            held.append(locking.hold(cell.out / LOCK, "out", cell.out, HOLDER))
        return _run_locked(cells, executor, registered, on_start, on_row, keep_rows,
                           max_failed)
    finally:
        for fd in held:
            locking.release(fd)


def _run_locked(cells: Sequence[Cell], executor: Executor, registered: Any,
                on_start: Callable[[int, int], None] | None,
                on_row: Callable[[int, TrialRow], None] | None,
                keep_rows: bool, max_failed: int | None) -> tuple[Outcome, ...]:
    """:func:`run_cells` once every directory is checked and locked."""
    jobs: list[Job] = []
    skipped: list[int] = []
    for index, cell in enumerate(cells):
        for where in (cell.experiment.settings.images, cell.experiment.settings.recordings):
            if where is not None:
                Path(where).mkdir(parents=True, exist_ok=True)
        # Trials whose LLM failed are run again; their rows go, and the new ones come.
        mine = [r for r in read_rows(cell.out) if r.status != "llm-failed"]
        done = {row_key(r) for r in mine}
        wanted = cell.experiment.specs()
        pending = [Job(index, cell.experiment.settings, s) for s in wanted if s.key not in done]
        jobs += pending
        skipped.append(len(wanted) - len(pending))
        rewrite_rows(cell.out, mine)  # drops a cut-off last line before appending
        del mine
    if on_start is not None:
        on_start(len(jobs), sum(skipped))
    ran = [0] * len(cells)
    failed: list[TrialRow] = []
    interrupted = False
    results = executor.run(jobs, registered)
    try:
        for finished in results:
            cell = cells[finished.cell]
            kept = cell.experiment.settings
            for rel, data in finished.pictures:
                where = kept.recordings if rel.endswith(".rrd") else kept.images
                if where is not None:
                    write_bytes(Path(where) / Path(rel).name, data)
            append_row(cell.out / ROWS, finished.row)
            ran[finished.cell] += 1
            row = finished.row
            log.info("task %s trial %d %s: rating %d, %s", row.task, row.trial, row.method,
                     row.rating, "success" if row.success else row.status)
            if on_row is not None:
                on_row(finished.cell, row)
            if row.status == "llm-failed":
                failed.append(row)
                if max_failed is not None and len(failed) >= max_failed:
                    raise LLMTransient(
                        f"{len(failed)} trials got no usable LLM answer (the last: {row.reason}); "
                        "stopped early, every finished trial is saved; rerun to retry them",
                        param="max_failed", value=max_failed)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        results.close()  # stops the work still under way
    outcomes = []
    for index, cell in enumerate(cells):
        if not interrupted:
            sort_rows_file(cell.out)
        mine = tuple(sorted(read_rows(cell.out), key=table_order)) if keep_rows else ()
        outcomes.append(Outcome(mine, ran[index], skipped[index], interrupted))
    return tuple(outcomes)


def write_reports(out: Path, rows: Sequence[TrialRow], seed: int = 0) -> Report:
    """Write the summary, with the methods' paired comparisons (their bootstrap drawn from
    ``seed``, the bench's), and the paper's two plots from ``rows``."""
    summary = summarize(rows)
    # Trials whose LLM failed say nothing of the methods: they are counted apart.
    counted = [r for r in rows if r.status != "llm-failed"]
    paired = paired_by_trial(counted, summary.method_names, seed)
    write_json(out / "summary.json", summary_to_dict(summary, paired))
    # Atomic as the other reports: a run that resumes this directory as soon as this
    # one lets go of its lock may write them at the same moment.
    write_text(out / "summary.md", summary_markdown(summary, paired=paired))
    plot_rating_vs_time(summary, out / "fig3_rating_vs_time.png")
    plot_rating_per_task(summary, out / "fig5_rating_per_task.png")
    return Report(summary, paired)


@dataclass(frozen=True)
class Report:
    """What :func:`write_reports` wrote: the summary and the paired comparisons (value ->
    comparisons)."""

    summary: Summary
    paired: Mapping[str, tuple[PairedComparison, ...]]
