"""``llm-grop sweep``: a grid of bench experiments from a sweep file, on one executor."""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from llm_grop.cli.bench import BENCH_DEFAULTS, TrialProgress, prepare_experiment
from llm_grop.cli.execution import execution_flags, execution_settings
from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import EPILOG, check_out_dir
from llm_grop.cli.settings import checked_settings
from llm_grop.errors import BadInput
from llm_grop.settings import in_words

if TYPE_CHECKING:
    from llm_grop.experiment.executors import Executor
    from llm_grop.experiment.runner import Cell
    from llm_grop.experiment.sweep import Sweep, Values



def cell_settings(values: Values, base: Path) -> dict[str, Any]:
    """The settings record's fields a sweep cell's values set (paths relative to ``base``);
    a value left out is left to the bench's default."""
    from llm_grop.experiment.sweep import LLM_KEYS, SWEPT
    from llm_grop.settings import door

    def path(p: str) -> str:
        return str(base / Path(p).expanduser())

    given: dict[str, Any] = {}
    for key, name in SWEPT.items():
        value = getattr(values, key)
        if value is None:
            continue
        if door(name).path is not None:
            value = tuple(map(path, value)) if isinstance(value, tuple) else path(value)
        given[name] = value
    if given.get("table") == "scene":
        del given["table"]
    llm = values.llm
    if llm is not None:
        given |= {name: getattr(llm, key) for key, name in LLM_KEYS.items()
                  if getattr(llm, key) is not None}
        if llm.replay is not None:
            given["replay"] = path(llm.replay)
        if llm.model is not None:
            # A GGUF file (embedded) is a path; a model's name is not.
            gguf = llm.backend in (None, "embedded") and llm.model.lower().endswith(".gguf")
            given["model"] = path(llm.model) if gguf else llm.model
    return given


def experiment_params(values: Values) -> dict[str, Any]:
    """The bench's experiment parameters a sweep cell's values set, on the bench's
    defaults: which tasks, trials and methods, and whether to draw pictures."""
    def joined(v: str | list[Any]) -> str:
        return v if isinstance(v, str) else ",".join(map(str, v))

    given = dict(BENCH_DEFAULTS)
    if values.tasks is not None:
        given["tasks_text"] = joined(values.tasks)
    if values.methods is not None:
        given["methods_text"] = joined(values.methods)
    if values.trials is not None:
        given["trials"] = values.trials
    if values.images is not None:
        given["no_images"] = not values.images
    return given


@click.command(epilog=EPILOG)
@VERBOSE
@click.argument("sweep_file", metavar="FILE.yaml",
                type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", "out_dir", required=True,
              type=click.Path(file_okay=False, path_type=Path),
              help="The sweep's directory: a results directory per cell, and the summary "
                   "across them; rerunning into it resumes.")
@execution_flags
@click.option("-q", "--quiet", is_flag=True, help="No progress bar or summary.")
def sweep(sweep_file: Path, out_dir: Path, quiet: bool, **flags: Any) -> None:
    """Run a grid of bench experiments (tasks, methods, chairs, tables, simulators, LLMs,
    weights, trials) from a sweep file, each cell in a directory of its own."""
    from llm_grop import locking
    from llm_grop.experiment.runner import HOLDER, LOCK, Cell
    from llm_grop.experiment.sweep import MARKER, load_sweep

    check_out_dir("out", out_dir)
    # A sweep or bench running in the directory refuses this one before any other work.
    locking.check(out_dir / LOCK, "out", out_dir, HOLDER)
    if out_dir.is_dir() and any(p.name != LOCK for p in out_dir.iterdir()) and not (
            out_dir / MARKER).exists():
        raise BadInput(f"--out {out_dir}: not empty and holds no {MARKER}; choose an empty "
                       "or new directory")
    plan = load_sweep(sweep_file)
    executor, threads, cache = execution_settings(**flags)
    cells = []
    for cell in plan.cells:
        try:
            settings = checked_settings(cell_settings(cell.values, plan.base), cache=cache)
            exp = prepare_experiment(settings, **experiment_params(cell.values),
                                     out_dir=out_dir / cell.name, threads=threads)
        except BadInput as exc:
            raise BadInput(f"{sweep_file}: cell {cell.name}: {in_words(exc, 'sweep')}") \
                from None
        cells.append(Cell(exp, out_dir / cell.name))
    out_dir.mkdir(parents=True, exist_ok=True)
    # Held from before the marker is written to after the last report, so that two sweeps
    # never share the directory, whichever started first.
    held = locking.hold(out_dir / LOCK, "out", out_dir, HOLDER)
    try:
        _run(sweep_file, out_dir, plan, cells, executor, quiet, flags["max_failed"])
    finally:
        locking.release(held)


def _run(sweep_file: Path, out_dir: Path, plan: Sweep, cells: list[Cell],
         executor: Executor, quiet: bool, max_failed: int | None) -> None:
    """Run the checked sweep ``plan`` into ``out_dir``, whose lock this process holds: its
    marker, every cell's trials, then the reports."""
    from rich.console import Console

    from llm_grop.experiment.executors import describe
    from llm_grop.experiment.runner import run_cells
    from llm_grop.experiment.summary import rich_table
    from llm_grop.experiment.sweep import MARKER
    from llm_grop.experiment.sweep_report import sweep_rows, write_sweep_reports
    from llm_grop.files.jsonio import write_json

    write_json(out_dir / MARKER, {"format": 1, "sweep": str(sweep_file), "axes": plan.axes,
                                  "cells": [{"name": c.name, "axes": dict(c.axes)}
                                            for c in plan.cells]})
    console = Console(stderr=True)
    t0 = time.perf_counter()
    with TrialProgress(console, quiet, out_dir,
                       label=lambda k: plan.cells[k].name) as progress:
        outcomes = run_cells(cells, executor, on_start=progress.start, on_row=progress.row,
                             keep_rows=False, max_failed=max_failed)
    wall = time.perf_counter() - t0
    if any(o.interrupted for o in outcomes):
        saved = sum(o.ran + o.skipped for o in outcomes)
        console.print(f"interrupted: {saved} finished trial(s) are saved in {out_dir}; "
                      "rerun the same command to resume", soft_wrap=True)
        raise click.exceptions.Exit(130)
    reports = write_sweep_reports(out_dir, plan, [c.experiment.seed for c in cells])
    if not quiet:
        out = Console()
        out.print(rich_table(f"Sweep {plan.path.name}: {len(reports)} cell(s), mean ± "
                             "standard error", *sweep_rows(plan, reports),
                             left=len(plan.axes) + 1))
        ran = sum(o.ran for o in outcomes)
        done = sum(o.skipped for o in outcomes)
        out.print(f"{ran} trial(s) run, {done} already done, {wall:.1f} s on "
                  f"{describe(executor)}; results in {out_dir}")
