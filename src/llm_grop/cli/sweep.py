"""``llm-grop sweep``: a grid of bench experiments from a sweep file, on one executor."""

from __future__ import annotations

import re
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from llm_grop.cli.bench import TrialProgress, bench, prepare_experiment
from llm_grop.cli.execution import execution_flags, execution_settings
from llm_grop.cli.logs import VERBOSE
from llm_grop.cli.options import EPILOG, check_out_dir
from llm_grop.errors import BadInput
from llm_grop.world.table import Table

if TYPE_CHECKING:
    from llm_grop.experiment.sweep import Values

#: The bench flag behind each sweep file field, for messages about a cell.
_FIELDS = {"--tasks": "tasks", "--methods": "methods", "--trials": "trials",
           "--chairs": "chairs", "--table": "table", "--simulator": "simulator",
           "--feasibility": "feasibility", "--weight": "weight", "--llm": "llm.backend",
           "--model": "llm.model", "--base-url": "llm.base_url", "--replay": "llm.replay",
           "--scene": "scene", "--preferences": "preferences"}
_FLAG = re.compile(r"^(--[a-z-]+)\b")
#: The sweep file field behind each API parameter an error may name, where they differ.
_PARAMS = {"method": "methods", "planner.w": "weight",
           "planner.fidelity_w_s_per_cm": "fidelity_weight", "llm": "llm.backend"}


def bench_params(values: Values, base: Path) -> dict[str, Any]:
    """What a sweep cell's values set of ``bench``'s parameters (paths relative to
    ``base``); a value left out is left to the bench's default."""
    def joined(v: str | list[Any]) -> str:
        return v if isinstance(v, str) else ",".join(map(str, v))

    def path(p: str) -> Path:
        return base / Path(p).expanduser()

    given: dict[str, Any] = {
        "trials": values.trials, "seed": values.seed, "chairs": values.chairs,
        "simulator": values.simulator, "feasibility": values.feasibility,
        "w": values.weight, "fidelity_w": values.fidelity_weight}
    if values.tasks is not None:
        given["tasks_text"] = joined(values.tasks)
    if values.methods is not None:
        given["methods_text"] = joined(values.methods)
    if values.scene is not None:
        given["scene_path"] = path(values.scene)
    if values.table not in (None, "scene"):
        given["table"] = Table.parse(values.table)
    if values.images is not None:
        given["no_images"] = not values.images
    if values.preferences is not None:
        given["preferences_file"] = path(values.preferences)
    llm = values.llm
    if llm is not None:
        given |= {"backend": llm.backend, "base_url": llm.base_url,
                  "temperature": llm.temperature}
        if llm.replay is not None:
            given["replay_path"] = path(llm.replay)
        if llm.model is not None:
            # A GGUF file (embedded) is a path; a model's name is not.
            gguf = llm.backend in (None, "embedded") and llm.model.lower().endswith(".gguf")
            given["model"] = str(path(llm.model)) if gguf else llm.model
    return {k: v for k, v in given.items() if v is not None}


def bench_defaults() -> dict[str, Any]:
    """``bench``'s parameters as its flags leave them when none is given (parsed under
    this command's context, so that ``-v`` keeps its count)."""
    return dict(bench.make_context("bench", [], parent=click.get_current_context()).params)


def _in_file(exc: BadInput, where: str) -> BadInput:
    """``exc`` about a bench flag or an API parameter, said of the sweep file's field
    instead."""
    if exc.param is not None:
        field = _PARAMS.get(exc.param, exc.param)
        named = field if exc.value is None else f"{field} {exc.value}"
        return BadInput(f"{where}: {named}: {exc.detail}")
    text = _FLAG.sub(lambda m: _FIELDS.get(m.group(1), m.group(1)), str(exc), count=1)
    return BadInput(f"{where}: {text}")


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
    from rich.console import Console

    from llm_grop.experiment.executors import describe
    from llm_grop.experiment.runner import Cell, run_cells
    from llm_grop.experiment.summary import rich_table
    from llm_grop.experiment.sweep import MARKER, load_sweep
    from llm_grop.experiment.sweep_report import sweep_rows, write_sweep_reports
    from llm_grop.world.jsonio import write_json

    check_out_dir("out", out_dir)
    if out_dir.is_dir() and any(out_dir.iterdir()) and not (out_dir / MARKER).exists():
        raise BadInput(f"--out {out_dir}: not empty and holds no {MARKER}; choose an empty "
                       "or new directory")
    plan = load_sweep(sweep_file)
    executor, threads, cache = execution_settings(**flags)
    defaults = bench_defaults()
    cells = []
    for cell in plan.cells:
        try:
            params = defaults | bench_params(cell.values, plan.base)
            exp = prepare_experiment(**(params | {"out_dir": out_dir / cell.name}),
                                     threads=threads, cache=cache)
        except BadInput as exc:
            raise _in_file(exc, f"{sweep_file}: cell {cell.name}") from None
        cells.append(Cell(exp, out_dir / cell.name))
    out_dir.mkdir(parents=True, exist_ok=True)
    write_json(out_dir / MARKER, {"format": 1, "sweep": str(sweep_file), "axes": plan.axes,
                                  "cells": [{"name": c.name, "axes": dict(c.axes)}
                                            for c in plan.cells]})
    console = Console(stderr=True)
    t0 = time.perf_counter()
    with TrialProgress(console, quiet, out_dir,
                       label=lambda k: plan.cells[k].name) as progress:
        outcomes = run_cells(cells, executor, on_start=progress.start, on_row=progress.row,
                             keep_rows=False, max_failed=flags["max_failed"])
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
