"""``llm-grop bench``: the paper's experiment (§IV), resumable, with a summary and plots."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, overload

import click

from llm_grop.cli.execution import execution_flags, execution_settings
from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import EPILOG, check_out_dir
from llm_grop.cli.settings import (
    ARRANGE_FIELDS,
    ATTEMPT_FIELDS,
    LLM_FIELDS,
    ROOM_FIELDS,
    checked_settings,
    flags,
)
from llm_grop.errors import BadInput

if TYPE_CHECKING:
    from rich.console import Console

    from llm_grop.experiment.runner import Experiment
    from llm_grop.settings import RunSettings


def parse_tasks(text: str, known: dict[int, Any]) -> tuple[int, ...]:
    """``"1-8"``, ``"1,3,5"``, or a tag such as ``paper`` or ``smoke`` -> task ids."""
    ids: list[int] = []
    for part in (p.strip() for p in text.split(",")):
        if not part:
            continue
        if part[0].isdigit():
            lo, _, hi = part.partition("-")
            try:
                span = range(int(lo), int(hi or lo) + 1)
            except ValueError:
                raise BadInput(f"{part!r} is not a task number or range",
                               param="tasks") from None
            if not span:
                raise BadInput(f"{part!r} is an empty range", param="tasks")
            ids += span
        else:
            tagged = [t for t, task in known.items() if part in task.tags]
            if not tagged:
                tags = sorted({g for task in known.values() for g in task.tags})
                raise BadInput(f"no task is tagged {part!r} (tags: {', '.join(tags)})",
                               param="tasks")
            ids += tagged
    unknown = [t for t in ids if t not in known]
    if unknown:
        raise BadInput(f"unknown task {unknown[0]} (tasks: {', '.join(map(str, known))})",
                       param="tasks")
    if not ids:
        raise BadInput("no task given", param="tasks")
    return tuple(dict.fromkeys(ids))


def parse_methods(text: str) -> tuple[str, ...]:
    """``"tpra,grop"`` -> registered method names (unknown ones are bad input)."""
    from llm_grop.methods.registry import get_method

    try:
        names = tuple(dict.fromkeys(get_method(m).name for m in text.split(",") if m.strip()))
    except BadInput as exc:
        if exc.param != "method":
            raise
        raise BadInput(exc.detail, param="methods") from None
    if not names:
        raise BadInput("no method given", param="methods")
    return names


def _check_tasks(tasks: tuple[int, ...], known: dict[int, Any], settings: RunSettings,
                 simulator: Any, scene: Any) -> None:
    """Unknown objects, bad preferences and objects the simulator cannot handle are
    reported before any trial runs (and writes its directory)."""
    from llm_grop.arrangement.preferences import read_preferences
    from llm_grop.assembly import arrange_options
    from llm_grop.world.catalog import Catalog
    from llm_grop.world.request import items_from_names

    catalog = Catalog.load(settings.catalog_files)
    options = arrange_options(settings)
    for t in tasks:
        items = items_from_names(known[t].objects, catalog, where=f"task {t}: objects")
        try:
            simulator.check(scene, items)
        except BadInput as exc:
            raise _for_task(t, exc) from None
        if options.preferences or options.preference_pool:
            try:
                read_preferences(options.preferences, options.preference_pool, items, catalog)
            except BadInput as exc:
                raise _for_task(t, exc) from None


def _for_task(task: int, exc: BadInput) -> BadInput:
    """``exc`` said of the paper's task ``task``, naming the same parameter."""
    if exc.param is None:
        return BadInput(f"task {task}: {exc}")
    return BadInput(f"task {task}: {exc.detail}", param=exc.param, value=exc.value)


#: The experiment's own parameters when no flag (or sweep key) sets them.
BENCH_DEFAULTS: dict[str, Any] = {"tasks_text": "paper", "trials": 20,
                                  "methods_text": "tpra,latp,grop,llm-grop",
                                  "no_images": False}


@click.command(epilog=EPILOG)
@VERBOSE
@click.option("--tasks", "tasks_text", default=BENCH_DEFAULTS["tasks_text"],
              show_default=True, help="Task ids, ranges or tags: 1-8, 1,3,5, paper, smoke.")
@click.option("--trials", default=BENCH_DEFAULTS["trials"], show_default=True,
              type=click.IntRange(1), help="Trials per task and method.")
@click.option("--methods", "methods_text", default=BENCH_DEFAULTS["methods_text"],
              show_default=True, help="Comma-separated methods.")
@click.option("--out", "out_dir", default=Path("bench"), show_default=True,
              type=click.Path(file_okay=False, path_type=Path),
              help="Results directory; rerunning into it resumes.")
@flags("method_options", "seed", "scene", "chairs", *ROOM_FIELDS, "task_files", help={
    "seed": "Seed of trial 0 (trial k: seed+k).",
    "chairs": "Chairs sampled near the table in every trial [default: the scene's own, "
              "else 1]."})
@click.option("--no-images", is_flag=True, help="Do not draw each trial's final table.")
@click.option("--rerun", "rerun_trials", is_flag=True,
              help="Write each trial's Rerun recording to OUT/recordings/ (needs the [viz] "
                   "extra; `llm-grop view` opens one).")
@flags(*ATTEMPT_FIELDS, *LLM_FIELDS, *ARRANGE_FIELDS, "guess")
@execution_flags
@click.option("-q", "--quiet", is_flag=True, help="No progress bar or summary.")
def bench(quiet: bool, **params: Any) -> None:
    """Run the paper's experiment: tasks x trials x methods, rated 1-5 (paper §IV)."""
    from rich.console import Console

    from llm_grop.experiment.executors import describe
    from llm_grop.experiment.runner import run_experiment, write_reports
    from llm_grop.experiment.summary import print_summary

    out_dir: Path = params["out_dir"]
    executor, threads, cache = execution_settings(**params)
    exp = prepare_experiment(checked_settings(params, cache=cache), tasks_text=params[
        "tasks_text"], trials=params["trials"], methods_text=params["methods_text"],
        out_dir=out_dir, no_images=params["no_images"], threads=threads,
        recordings=params["rerun_trials"])
    console = Console(stderr=True)
    t0 = time.perf_counter()
    with TrialProgress(console, quiet, out_dir) as progress:
        outcome = run_experiment(exp, out_dir, executor=executor, on_start=progress.start,
                                 on_row=progress.row, max_failed=params["max_failed"])
    wall = time.perf_counter() - t0
    if outcome.interrupted:
        console.print(f"interrupted: {len(outcome.rows)} finished trial(s) are saved in "
                      f"{out_dir / 'trials.jsonl'}; rerun the same command to resume",
                      soft_wrap=True)
        raise click.exceptions.Exit(130)
    report = write_reports(out_dir, outcome.rows, exp.seed)
    if not quiet:
        out = Console()
        print_summary(report.summary, out, paired=report.paired)
        out.print(f"{outcome.ran} trial(s) run, {outcome.skipped} already done, "
                  f"{wall:.1f} s on {describe(executor)}; results in {out_dir}")


def prepare_experiment(settings: RunSettings, *, tasks_text: str, trials: int,
                       methods_text: str, out_dir: Path, no_images: bool,
                       threads: int | None, recordings: bool = False) -> Experiment:
    """The experiment of ``settings`` (trial 0's seed, the room, the planner, the LLM...)
    over the tasks ``tasks_text``, ``trials`` trials each, of the methods ``methods_text``,
    into ``out_dir``; every input checked (unknown components, tasks, objects and
    preferences, the output directory) before any trial runs. ``threads`` are the embedded
    model's per worker; with ``recordings`` each trial writes its Rerun recording to
    ``out_dir/recordings``.
    """
    from llm_grop.assembly import (
        make_backend,
        make_simulator,
        resolve_feasibility,
        resolve_llm,
        seat_scene_diners,
        with_robot_settings,
    )
    from llm_grop.experiment.runner import Experiment
    from llm_grop.experiment.trial import TrialSettings
    from llm_grop.files.scene_file import load_scene, set_target_top
    from llm_grop.llm.registry import BACKENDS
    from llm_grop.methods.registry import get_method
    from llm_grop.planning.feasibility import feasibility_profile
    from llm_grop.world.table import Table
    from llm_grop.world.tasks import load_tasks

    # Absolute, so that workers on other machines find the same files.
    absolute = {name: _absolute(getattr(settings, name)) for name in
                ("scene", "replay", "preferences_file") if getattr(settings, name)}
    absolute |= {name: tuple(str(_absolute(p)) for p in getattr(settings, name))
                 for name in ("task_files", "catalog_files")}
    if settings.model and Path(settings.model).expanduser().is_file():
        absolute["model"] = _absolute(settings.model)  # a GGUF file
    settings = settings.with_values(**absolute)
    check_out_dir("out", out_dir)  # before any model is loaded or trial run
    if recordings:
        from llm_grop.recording.episode import check_extra

        check_extra("rerun")
        if (out_dir / "recordings").exists() and not (out_dir / "recordings").is_dir():
            raise BadInput(f"{out_dir / 'recordings'} is a file, where each trial's "
                           "recording goes; remove it", param="out", value=out_dir)
    if not no_images and (out_dir / "images").exists() and not (out_dir / "images").is_dir():
        raise BadInput(f"{out_dir / 'images'} is a file, where each trial's picture goes; "
                       "remove it or pass --no-images", param="out", value=out_dir)
    known = load_tasks(settings.task_files)
    tasks = parse_tasks(tasks_text, known)
    methods = parse_methods(methods_text)
    # Unknown or broken components are reported before any trial runs, and their names
    # are written canonically into the experiment's identity.
    sim = make_simulator(settings)
    settings = resolve_feasibility(settings, sim)  # the experiment names the profile used
    feasibility_profile(settings.feasibility)
    if not no_images and sim.supports_pictures:
        sim.check_rendering()  # a simulator that renders says now if it cannot
    settings = settings.with_values(simulator=sim.name)
    # Each method is built with the options now, so a bad one is reported before any trial.
    if any(get_method(m, dict(settings.method_options)).arrangement.uses_llm
           for m in methods):
        # The driver chooses once for every trial, and the experiment names the choice.
        settings, _ = resolve_llm(settings)
        settings = settings.with_values(llm=BACKENDS.key(settings.llm))
        make_backend(settings)
    scene = load_scene(settings.scene)  # a bad scene is reported before any trial runs
    if settings.table is not None:
        scene = set_target_top(scene, Table.parse(settings.table),
                               keep_chairs=settings.chairs is None)
    scene = seat_scene_diners(scene, settings)  # too many seats for a scene's, before any trial
    scene = with_robot_settings(scene, settings)
    _check_tasks(tasks, known, settings, sim, scene)
    return Experiment(tasks, trials, methods, TrialSettings(
        settings.with_values(rerun=None, mcap=None),
        images=None if no_images else str(out_dir / "images"), llm_threads=threads,
        recordings=str(out_dir / "recordings") if recordings else None), settings.seed)


@overload
def _absolute(path: None) -> None: ...
@overload
def _absolute(path: str | Path) -> Path: ...
def _absolute(path: str | Path | None) -> Path | None:
    """``path`` made absolute (``~`` expanded), or ``None``."""
    return None if path is None else Path(path).expanduser().absolute()


class TrialProgress:
    """A progress bar over trials (on stderr; nothing when ``quiet``) whose :meth:`start`
    and :meth:`row` are the runner's callbacks, for results in ``where``; ``label`` names a
    row's experiment (a sweep's cell) in the bar."""

    def __init__(self, console: Console, quiet: bool, where: Path,
                 label: Callable[[int], str] | None = None) -> None:
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self.console, self.quiet, self.where, self.label = console, quiet, where, label
        self.progress = Progress(TextColumn("{task.description}"), BarColumn(),
                                 MofNCompleteColumn(), TimeElapsedColumn(),
                                 TimeRemainingColumn(), console=console, disable=quiet)
        self.bar = self.progress.add_task("trials", total=None)

    def __enter__(self) -> TrialProgress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.progress.stop()

    def start(self, pending: int, skipped: int) -> None:
        """The runner's ``on_start``: the bar shows from now on (a refusal before it is
        printed alone)."""
        self.progress.start()
        self.progress.update(self.bar, total=pending)
        if skipped and not self.quiet:
            self.console.print(f"resuming: {skipped} trial(s) already done in {self.where}")

    def row(self, *args: Any) -> None:
        """The runner's ``on_row``: ``(row)`` for a bench, ``(cell, row)`` for a sweep."""
        from llm_grop.cli.console import print_warnings

        *cell, row = args
        where = f"{self.label(cell[0])}: " if cell and self.label is not None else ""
        name = f"{where}task {row.task} trial {row.trial} {row.method}"
        self.progress.update(self.bar, advance=1, description=f"{name}: rating {row.rating}")
        if not self.quiet and row.planned is not None:
            print_warnings(row.planned.warnings, self.console, name)
