"""One trial of the paper's experiment (§IV): a method on a task with a seed, rated.

A trial runs the whole pipeline (:func:`llm_grop.api.run`), rates the final arrangement
with the automatic rater, draws the final table as the paper's raters saw it, and returns
one :class:`~llm_grop.world.contract.TrialRow`: the contract's run JSON (without the LLM's
call log) plus the rating, its checks and per-trial counts. A trial whose arrangement or
plan is infeasible still gives a row (``status`` ``"infeasible"``, nothing on the table,
rated accordingly), and so does one whose LLM could not answer after its retries
(``"llm-failed"``, with the reason), which the summary leaves out and a rerun retries.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from llm_grop.api import run
from llm_grop.arrangement.diners import seat_items
from llm_grop.arrangement.pipeline import ArrangeOptions
from llm_grop.errors import Infeasible, LLMTransient
from llm_grop.evaluation.rater import rate
from llm_grop.execution import ExecutionPolicy
from llm_grop.execution.policy import NAV_ATTEMPTS
from llm_grop.llm.base import LLM, BackendOptions, CallLog
from llm_grop.llm.cache import LLMCache
from llm_grop.llm.registry import create_llm
from llm_grop.methods.registry import get_method
from llm_grop.planning.utility import GropOptions
from llm_grop.render.raster import save_rgb_png
from llm_grop.render.table import draw_arrangement
from llm_grop.simulation.registry import DEFAULT_SIMULATOR, create_simulator
from llm_grop.world.arrangement import Arrangement
from llm_grop.world.catalog import Catalog
from llm_grop.world.contract import TrialRow
from llm_grop.world.request import items_from_names
from llm_grop.world.run_json import run_doc
from llm_grop.world.scene import Scene
from llm_grop.world.scene_file import load_scene, set_target_top
from llm_grop.world.serialize import arrangement_doc
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
    """What every trial of an experiment shares (picklable, for worker processes).

    ``scene``: a scene YAML path or ``None`` for the packaged room; ``chairs``: chairs per
    episode; ``table``: the target table's top as ``--table`` takes it (``"1.8x0.9"``,
    ``"round:1.2"``; ``None``: the scene's); ``w``: GROP's utility weight, seconds;
    ``simulator``: the simulator that executes every plan; ``feasibility``: the planner's
    feasibility profile; ``images``: where to draw each trial's final table (``None``: no
    pictures); ``llm_cache``: the LLM cache's directory (``None``: no cache), which changes
    no answer and so is no part of the experiment's identity; ``nav_attempts`` and
    ``manip_attempts``: the executive's attempt counts (``None``: the method's);
    ``grasp``: how MuJoCo's hand holds (``fix`` or ``friction``); ``truth``: the
    profile the 2D simulator draws from (``None``: its own).
    """

    backend: str = "replay"
    llm_options: BackendOptions = field(default_factory=BackendOptions)
    arrange: ArrangeOptions = field(default_factory=ArrangeOptions)
    scene: str | None = None
    chairs: int | None = 1
    w: float = 40.0
    task_files: tuple[str, ...] = ()
    catalog_files: tuple[str, ...] = ()
    images: str | None = None
    simulator: str = DEFAULT_SIMULATOR
    feasibility: str = "default"
    table: str | None = None
    fidelity_w_s_per_cm: float = 1.0
    llm_cache: str | None = None
    nav_attempts: int = NAV_ATTEMPTS
    manip_attempts: int | None = None
    grasp: str = "fix"
    truth: str | None = None


class TrialRunner:
    """Runs trials with one LLM, catalog and scene, loaded once (one per worker process)."""

    def __init__(self, settings: TrialSettings) -> None:
        self.settings = settings
        self.catalog = Catalog.load(settings.catalog_files)
        self.tasks: dict[int, Task] = load_tasks(settings.task_files)
        self.scene: Scene = load_scene(settings.scene)
        if settings.table is not None:
            self.scene = set_target_top(self.scene, Table.parse(settings.table),
                                        keep_chairs=settings.chairs is None)
        self.simulator = create_simulator(settings.simulator, grasp=settings.grasp,
                                          truth=settings.truth)
        self._backend: LLM | None = None

    def llm(self) -> CallLog:
        """A fresh call log for one trial over the shared backend, which is created on first
        use (methods without an LLM never load a model)."""
        if self._backend is None:
            self._backend = create_llm(self.settings.backend, self.settings.llm_options)
        cache = self.settings.llm_cache
        return CallLog(self._backend, cache=LLMCache(cache) if cache is not None else None)

    def __call__(self, spec: TrialSpec, images: Path | None = None) -> TrialRow:
        """The trial's row; its pictures go to ``images`` when given, else to the
        settings' directory (the row names them relative to the results directory either
        way)."""
        task = self.tasks[spec.task]
        llm_log = self.llm() if get_method(spec.method).uses_llm else None
        # A scene that seats several diners sets the task's objects once for each of them.
        requested = [i.name for i in seat_items(items_from_names(task.objects, self.catalog),
                                                self.scene.target_top)]
        episode: dict[str, Any]
        try:
            result = run(task=spec.task, tasks=self.tasks, method=spec.method, scene=self.scene,
                         chairs=self.settings.chairs, seed=spec.seed,
                         llm=llm_log if llm_log is not None else "replay", catalog=self.catalog,
                         options=self.settings.arrange, planner=GropOptions(
                             w=self.settings.w,
                             fidelity_w_s_per_cm=self.settings.fidelity_w_s_per_cm),
                         simulator=self.simulator, feasibility=self.settings.feasibility,
                         execution=ExecutionPolicy(
                             nav_attempts=self.settings.nav_attempts,
                             manip_attempts=self.settings.manip_attempts))
        except (Infeasible, LLMTransient) as exc:
            # A trial whose LLM did not answer after its retries is kept as such, and the
            # bench goes on; a rerun asks again. A wrong key, model or replay file is no
            # passing failure: it stops the bench.
            status = "infeasible" if isinstance(exc, Infeasible) else "llm-failed"
            log.info("task %d trial %d %s: %s: %s", spec.task, spec.trial, spec.method,
                     status, exc)
            final = Arrangement(task.request, self.scene.target_top, ())
            items = list(requested)
            episode = {"method": spec.method, "task": spec.task, "seed": spec.seed,
                       "request": task.request, "success": False, "execution_time_s": None,
                       "planning_time_s": None, "failures": 0, "unplaced": items,
                       "steps": [], "final": arrangement_doc(final),
                       "simulator": self.settings.simulator, "status": status,
                       "reason": str(exc), "retries": 0}
        else:
            final = result.final
            doc = run_doc(result, llm_log=False)
            episode = {k: getattr(doc, k) for k in doc.model_fields_set} | {
                "status": "ok", "retries": sum(s.attempt > 1 for s in result.execution.steps)}
        calls = llm_log.calls if llm_log else []
        rating = rate(episode["final"], requested=requested, catalog=self.catalog)
        extra: dict[str, Any] = {}
        if images is None and self.settings.images is not None:
            images = Path(self.settings.images)
        if images is not None:
            extra["image"] = self._draw(spec, task, final, images)
            if episode["status"] == "ok" and hasattr(self.simulator, "picture"):
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
        name = f"task{spec.task}_trial{spec.trial:02d}_{spec.method}_render.png"
        save_rgb_png(self.simulator.picture("table"),  # type: ignore[attr-defined]
                     images / name)
        return f"images/{name}"

    def _draw(self, spec: TrialSpec, task: Task, final: Arrangement, images: Path) -> str:
        name = f"task{spec.task}_trial{spec.trial:02d}_{spec.method}.png"
        draw_arrangement(final, images / name, title="Requested: " + ", ".join(task.objects))
        return f"images/{name}"
