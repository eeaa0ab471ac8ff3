"""The paper's experiment (§IV): tasks x trials x methods, resumable, in parallel.

An output directory holds one experiment:

* ``experiment.json``: what makes results comparable (LLM, scene, chairs, sampler and
  planner settings, simulator, task and catalog files, version). A directory holding a different
  experiment is refused, so results are never mixed.
* ``trials.jsonl``: one :class:`~llm_grop.world.contract.TrialRow` per finished trial,
  appended and flushed as each one ends, so
  an interrupted run loses no finished trial. A rerun skips the trials already there.
  When every trial is done the file is rewritten in ``(task, trial, method)`` order.
* ``images/``: each trial's final table, the requested objects listed at the top.
* ``summary.json``, ``summary.md`` and the paper's plots, ``fig3_rating_vs_time.png`` and
  ``fig5_rating_per_task.png``, made from every row.

Trial ``k`` of every task uses seed ``seed + k`` for every method, so methods see the same
scenes and chairs and the comparison is paired.

Worker processes find installed plugins themselves; methods, backends and simulators
registered at run time are handed to them (:func:`llm_grop.plugins.registered`).
"""

from __future__ import annotations

import hashlib
import json
import logging
import multiprocessing
import os
import signal
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass
from importlib import metadata, resources
from pathlib import Path
from typing import Any

from llm_grop import plugins
from llm_grop.errors import BadInput
from llm_grop.experiment.plots import plot_rating_per_task, plot_rating_vs_time
from llm_grop.experiment.summary import Summary, summarize, summary_markdown, summary_to_dict
from llm_grop.experiment.trial import TrialRunner, TrialSettings, TrialSpec
from llm_grop.llm.registry import BACKENDS
from llm_grop.methods.registry import METHODS
from llm_grop.simulation.registry import SIMULATORS
from llm_grop.world.contract import TrialRow
from llm_grop.world.jsonio import write_json
from llm_grop.world.serialize import read_doc

log = logging.getLogger(__name__)

ROWS = "trials.jsonl"
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
    """The settings that decide a trial's result; equal identities may share a directory."""
    s = exp.settings
    tasks = resources.files("llm_grop").joinpath("data/tasks.yaml").read_bytes()
    catalog = resources.files("llm_grop").joinpath("data/catalog.yaml").read_bytes()
    opts = s.llm_options
    return {
        "format": 1,
        "version": metadata.version("llm-grop"),
        "llm": {"backend": s.backend, "model": opts.model, "base_url": opts.base_url,
                "replay": _digest([opts.replay_path]) if opts.replay_path else None},
        "arrange": json.loads(json.dumps(asdict(s.arrange), default=str)),
        "scene": _digest([s.scene]) if s.scene else "packaged",
        "chairs": s.chairs,
        # Absent for the scene's own table, so directories written before --table resume.
        **({"table": s.table} if s.table is not None else {}),
        "w": s.w,
        "fidelity_weight_s_per_cm": s.fidelity_w_s_per_cm,
        "simulator": s.simulator,
        # Absent for the default, so directories written before profiles existed resume.
        **({"feasibility": s.feasibility} if s.feasibility != "default" else {}),
        "plugins": _plugin_origins(exp),
        "seed": exp.seed,
        "tasks": hashlib.sha256(tasks).hexdigest()[:16] + (
            "+" + _digest(s.task_files) if s.task_files else ""),
        "catalog": hashlib.sha256(catalog).hexdigest()[:16] + (
            "+" + _digest(s.catalog_files) if s.catalog_files else ""),
    }


def _plugin_origins(exp: Experiment) -> dict[str, str]:
    """Where each component the experiment uses comes from, when llm-grop does not ship it
    (a plugin's version decides its results as llm-grop's own version does)."""
    used = [(BACKENDS, exp.settings.backend), (SIMULATORS, exp.settings.simulator),
            *((METHODS, m) for m in exp.methods)]
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
            raise BadInput(f"--out {out}: {IDENTITY} is unreadable; choose another "
                           "directory") from None
        diff = sorted(k for k in mine.keys() | theirs.keys() if mine.get(k) != theirs.get(k))
        if diff:
            raise BadInput(f"--out {out}: holds another experiment's results (different "
                           f"{', '.join(diff)}); choose another directory")
        return
    if out.exists() and any(out.iterdir()):
        raise BadInput(f"--out {out}: not empty and holds no {IDENTITY}; choose an empty "
                       "or new directory")
    out.mkdir(parents=True, exist_ok=True)
    write_json(marker, mine)


def read_rows(out: Path) -> list[TrialRow]:
    """The finished trials' rows; a last line cut off by a crash is dropped."""
    path = out / ROWS
    if not path.exists():
        return []
    rows = []
    lines = path.read_text(encoding="utf-8").splitlines()
    for i, line in enumerate(lines):
        try:
            data = json.loads(line)
        except ValueError:
            if i == len(lines) - 1:
                break
            raise BadInput(f"{path} line {i + 1}: not a JSON row") from None
        rows.append(read_doc(TrialRow, data, f"{path} line {i + 1}"))
    return rows


def _key(row: TrialRow) -> tuple[str, int, int]:
    return (row.method, row.task, row.trial)


def _sort_key(row: TrialRow) -> tuple[int, int, str]:
    return (row.task, row.trial, row.method)


def _line(row: TrialRow) -> str:
    return json.dumps(row.to_json(), separators=(",", ":")) + "\n"


# Each worker process keeps one runner (one LLM, catalog and scene) for all its trials.
_RUNNER: TrialRunner | None = None
# Why a worker could not start; reported with its first trial, because a pool restarts a
# worker whose initializer raises, forever.
_START_ERROR: Exception | None = None


def _init_worker(settings: TrialSettings, registered: dict[str, tuple[str, dict[str, Any]]],
                 log_level: int) -> None:
    global _RUNNER, _START_ERROR
    logging.basicConfig(format="llm-grop: worker %(process)d: %(levelname)s: %(name)s: "
                        "%(message)s")
    logging.getLogger("llm_grop").setLevel(log_level)
    # The parent handles Ctrl-C and stops the workers; they must not die mid-row.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        plugins.restore(registered)
        _RUNNER = TrialRunner(settings)
    except Exception as exc:  # noqa: BLE001 - handed to the parent with the first trial
        _START_ERROR = exc


def _work(spec: TrialSpec) -> TrialRow:
    if _START_ERROR is not None:
        raise _START_ERROR
    assert _RUNNER is not None
    return _RUNNER(spec)


def _results(pending: list[TrialSpec], settings: TrialSettings, workers: int,
             registered: dict[str, tuple[str, dict[str, Any]]]) -> Iterator[TrialRow]:
    if workers <= 1:
        runner = TrialRunner(settings)
        for spec in pending:
            yield runner(spec)
        return
    ctx = multiprocessing.get_context("spawn")
    pool = ctx.Pool(workers, initializer=_init_worker,
                    initargs=(settings, registered, log.getEffectiveLevel()))
    try:
        yield from pool.imap_unordered(_work, pending, chunksize=1)
        pool.close()
    finally:
        pool.terminate()
        pool.join()


def run_experiment(exp: Experiment, out: Path, *, workers: int = 1,
                   on_start: Callable[[int, int], None] | None = None,
                   on_row: Callable[[TrialRow], None] | None = None) -> Outcome:
    """Run the trials of ``exp`` not yet in ``out``; returns every row there.

    ``on_start(pending, skipped)`` is called once, ``on_row`` after each finished trial.
    """
    # Checked before the directory is made: an entry that cannot reach workers fails now.
    used = {BACKENDS.group: [exp.settings.backend], SIMULATORS.group: [exp.settings.simulator],
            METHODS.group: list(exp.methods)}
    registered = plugins.registered(used) if workers > 1 else {}
    prepare_dir(out, exp)
    if exp.settings.images is not None:
        Path(exp.settings.images).mkdir(parents=True, exist_ok=True)
    rows = read_rows(out)
    done = {_key(r) for r in rows}
    wanted = exp.specs()
    pending = [s for s in wanted if s.key not in done]
    if on_start is not None:
        on_start(len(pending), len(wanted) - len(pending))
    ran, interrupted = 0, False
    _rewrite(out, rows)  # drops a cut-off last line before appending
    try:
        with (out / ROWS).open("a", encoding="utf-8") as f:
            for row in _results(pending, exp.settings, workers, registered):
                f.write(_line(row))
                f.flush()
                os.fsync(f.fileno())
                rows.append(row)
                log.info("task %s trial %d %s: rating %d, %s", row.task, row.trial, row.method,
                         row.rating, "success" if row.success else row.status)
                ran += 1
                if on_row is not None:
                    on_row(row)
    except KeyboardInterrupt:
        interrupted = True
    if not interrupted:
        rows.sort(key=_sort_key)
        _rewrite(out, rows)
    return Outcome(tuple(sorted(rows, key=_sort_key)), ran, len(wanted) - len(pending),
                   interrupted)


def _rewrite(out: Path, rows: list[TrialRow]) -> None:
    """Write ``rows`` as the results file, atomically."""
    tmp = out / f".{ROWS}.tmp"
    with tmp.open("w", encoding="utf-8") as f:
        for row in rows:
            f.write(_line(row))
        f.flush()
        os.fsync(f.fileno())
    tmp.replace(out / ROWS)


def write_reports(out: Path, rows: Sequence[TrialRow]) -> Summary:
    """Write the summary and the paper's two plots from ``rows``; returns the summary."""
    summary = summarize(rows)
    write_json(out / "summary.json", summary_to_dict(summary))
    (out / "summary.md").write_text(summary_markdown(summary), encoding="utf-8")
    plot_rating_vs_time(summary, out / "fig3_rating_vs_time.png")
    plot_rating_per_task(summary, out / "fig5_rating_per_task.png")
    return summary
