"""One trial of the paper's experiment (§IV): a method on a task with a seed, rated.

A trial runs the whole pipeline (:func:`llm_grop.api.run`), rates the final arrangement
with the automatic rater, draws the final table as the paper's raters saw it, and returns
one :class:`~llm_grop.contract.models.TrialRow`: the contract's run JSON (without the LLM's
call log) plus the rating, its checks and per-trial counts. A trial whose arrangement or
plan is infeasible still gives a row (``status`` ``"infeasible"``, nothing on the table,
rated accordingly), and so does one whose LLM could not answer after its retries
(``"llm-failed"``, with the reason), which the summary leaves out and a rerun retries.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from llm_grop.api import run
from llm_grop.arrangement.diners import seat_items
from llm_grop.assembly import call_log, make_backend, make_simulator, seat_scene_diners
from llm_grop.contract.models import TrialRow
from llm_grop.contract.run_json import run_doc
from llm_grop.contract.serialize import arrangement_doc
from llm_grop.errors import Infeasible, LLMAnswerUnusable, LLMTransient
from llm_grop.evaluation.rater import rate
from llm_grop.files.scene_file import load_scene, set_target_top
from llm_grop.llm.base import LLM, BackendOptions, CallLog
from llm_grop.methods.registry import get_method
from llm_grop.render.raster import save_rgb_png
from llm_grop.render.table import draw_arrangement
from llm_grop.settings import DEFAULTS, RunSettings
from llm_grop.world.arrangement import Arrangement
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import items_from_names
from llm_grop.world.scene import Scene
from llm_grop.world.table import Table
from llm_grop.world.tasks import Task, load_tasks

log = logging.getLogger(__name__)

#: Trial-row fields that hold wall-clock measurements.
TIMING_FIELDS = ("planning_time_s", "llm_time_s")
#: Trial-row fields that depend on how the experiment ran (wall clocks, and which trial
#: asked the shared LLM cache first); everything else repeats exactly for a seed.
RUN_DEPENDENT_FIELDS = (*TIMING_FIELDS, "llm_cache_hits")


@dataclass(frozen=True)
class TrialSpec:
    """Which trial: ``method`` on task ``task``, trial number ``trial`` with ``seed``."""

    method: str
    task: int
    trial: int
    seed: int

    @property
    def key(self) -> tuple[str, int, int]:
        """``(method, task, trial)``: what identifies a row in the results."""
        return (self.method, self.task, self.trial)


@dataclass(frozen=True)
class TrialSettings:
    """What every trial of an experiment shares (picklable, for worker processes): the
    run's settings record (each trial sets its own method, task and seed), where to draw
    each trial's final table (``images``; ``None``: no pictures), where to write each
    trial's Rerun recording (``recordings``; ``None``: none) and the embedded model's
    CPU threads in each worker (``llm_threads``; ``None``: all cores)."""

    run: RunSettings = DEFAULTS
    images: str | None = None
    llm_threads: int | None = None
    recordings: str | None = None

    @classmethod
    def of(cls, images: str | None = None, llm_threads: int | None = None,
           **fields: Any) -> TrialSettings:
        """Settings whose record has ``fields`` (by name: ``simulator="mujoco"``)."""
        return cls(RunSettings.make(fields), images, llm_threads)

    @property
    def simulator(self) -> str:
        """The simulator every trial runs on."""
        return self.run.simulator


class TrialRunner:
    """Runs trials with one LLM, catalog and scene, loaded once (one per worker process)."""

    def __init__(self, settings: TrialSettings) -> None:
        self.settings = settings
        s = settings.run
        self.catalog = Catalog.load(s.catalog_files)
        self.tasks: dict[int, Task] = load_tasks(s.task_files)
        scene = load_scene(s.scene)
        if s.table is not None:
            scene = set_target_top(scene, Table.parse(s.table))
        self.scene: Scene = seat_scene_diners(scene, s)
        self.top = self.scene.target_top
        self.simulator = make_simulator(s)
        self._backend: LLM | None = None

    def llm(self) -> CallLog:
        """A fresh call log for one trial over the shared backend, which is created on first
        use (methods without an LLM never load a model)."""
        s = self.settings.run
        if self._backend is None:
            self._backend = make_backend(s, BackendOptions(n_threads=self.settings.llm_threads))
        return call_log(self._backend, cache=s.cache, max_answer_bytes=s.max_answer_bytes)

    def __call__(self, spec: TrialSpec, images: Path | None = None,
                 recordings: Path | None = None) -> TrialRow:
        """The trial's row; its pictures go to ``images`` and its recording to
        ``recordings`` when given, else to the settings' directories (the row names them
        relative to the results directory either way)."""
        task = self.tasks[spec.task]
        if recordings is None and self.settings.recordings is not None:
            recordings = Path(self.settings.recordings)
        # One recording per trial, named as its pictures are (a path in the record shared
        # by every trial would have them overwrite each other).
        recording = f"{_stem(spec)}.rrd" if recordings is not None else None
        settings = self.settings.run.with_values(
            method=spec.method, task=spec.task, seed=spec.seed,
            rerun=str(recordings / recording) if recordings and recording else None,
            mcap=None)
        llm_log = self.llm() if get_method(spec.method, dict(settings.method_options)
                                           ).arrangement.uses_llm else None
        # A scene that seats several diners sets the task's objects once for each of them.
        requested = [i.name for i in seat_items(items_from_names(task.objects, self.catalog),
                                                self.top)]
        episode: dict[str, Any]
        try:
            result = run(settings=settings, llm=llm_log, simulator=self.simulator,
                         scene=self.scene, catalog=self.catalog, tasks=self.tasks)
        except (Infeasible, LLMTransient, LLMAnswerUnusable) as exc:
            # A trial whose LLM did not answer after its retries, or answered nothing
            # usable, is kept as such, and the bench goes on; a rerun asks again. A wrong
            # key, model or replay file is no passing failure: it stops the bench.
            status = "infeasible" if isinstance(exc, Infeasible) else "llm-failed"
            log.info("task %d trial %d %s: %s: %s", spec.task, spec.trial, spec.method,
                     status, exc)
            final = Arrangement(task.request, self.top, ())
            items = list(requested)
            episode = {"method": spec.method, "task": spec.task, "seed": spec.seed,
                       "request": task.request, "success": False, "execution_time_s": None,
                       "planning_time_s": None, "failures": 0, "unplaced": items,
                       "steps": [], "final": arrangement_doc(final),
                       "simulator": self.simulator.name, "status": status,
                       "reason": str(exc), "retries": 0}
        else:
            final = result.final
            doc = run_doc(result, llm_log=False)
            episode = {k: getattr(doc, k) for k in doc.model_fields_set} | {
                "status": "ok", "retries": sum(s.attempt > 1 for s in result.execution.steps)}
            if recording is not None:
                episode["recording"] = f"recordings/{recording}"
        calls = llm_log.calls if llm_log else []
        rating = rate(episode["final"], requested=requested, catalog=self.catalog)
        extra: dict[str, Any] = {}
        if images is None and self.settings.images is not None:
            images = Path(self.settings.images)
        if images is not None:
            extra["image"] = self._draw(spec, task, final, images)
            if episode["status"] == "ok" and self.simulator.supports_pictures:
                extra["render"] = self._render(spec, images)
        return TrialRow(
            **episode, trial=spec.trial, llm_calls=len(calls),
            llm_prompt_tokens=sum(c.prompt_tokens or 0 for c in calls),
            llm_completion_tokens=sum(c.completion_tokens or 0 for c in calls),
            llm_time_s=round(llm_log.wall_s, 4) if llm_log else 0.0,
            llm_cache_hits=llm_log.cache_hits if llm_log else 0,
            rating=rating.score, rating_explanation=rating.doc(),
            requested=list(task.objects), **extra)

    def _render(self, spec: TrialSpec, images: Path) -> str:
        """Save the simulator's top-down render of the final table."""
        name = f"{_stem(spec)}_render.png"
        save_rgb_png(self.simulator.picture("table"), images / name)
        return f"images/{name}"

    def _draw(self, spec: TrialSpec, task: Task, final: Arrangement, images: Path) -> str:
        name = f"{_stem(spec)}.png"
        draw_arrangement(final, images / name, title="Requested: " + ", ".join(task.objects))
        return f"images/{name}"


def _stem(spec: TrialSpec) -> str:
    """The name of a trial's files without their suffix."""
    return f"task{spec.task}_trial{spec.trial:02d}_{spec.method}"
