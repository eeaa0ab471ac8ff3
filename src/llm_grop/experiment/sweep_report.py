"""A sweep's reports: each cell's own (as a bench writes them), and one across the cells.

The sweep's directory gets ``summary.md`` (a row per cell and method: the grid's values,
trials, rating, execution time and success rate, each mean ± standard error),
``summary.json`` (each cell's grid values and its full bench summary, paired comparisons
included) and ``fig_sweep.png`` (:func:`~llm_grop.experiment.plots.plot_sweep`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from llm_grop.experiment.plots import plot_sweep
from llm_grop.experiment.runner import Report, read_rows, write_reports
from llm_grop.experiment.summary import md_row, mean_se, rate_text, summary_to_dict
from llm_grop.experiment.sweep import Sweep
from llm_grop.files.jsonio import write_json, write_text

#: What :func:`write_sweep_reports` writes into the sweep's directory.
FILES = ("summary.md", "summary.json", "fig_sweep.png")


@dataclass(frozen=True)
class CellReport:
    """One cell's name, grid values (key -> label) and bench report."""

    name: str
    axes: dict[str, str]
    report: Report


def write_sweep_reports(out: Path, sweep: Sweep, seeds: Sequence[int]) -> list[CellReport]:
    """Write every cell's reports into its directory (from its rows, one cell in memory
    at a time; ``seeds`` are the cells' experiments' seeds), then the sweep's own into
    ``out``."""
    reports = [CellReport(cell.name, dict(cell.axes),
                          write_reports(out / cell.name, read_rows(out / cell.name), seed))
               for cell, seed in zip(sweep.cells, seeds, strict=True)]
    write_json(out / "summary.json", sweep_to_dict(sweep, reports))
    write_text(out / "summary.md", sweep_markdown(sweep, reports))
    plot_sweep([(r.name, r.report.summary) for r in reports], out / "fig_sweep.png")
    return reports


def sweep_to_dict(sweep: Sweep, reports: Sequence[CellReport]) -> dict[str, Any]:
    """The sweep's summary as plain JSON values (times in seconds)."""
    return {"sweep": str(sweep.path), "axes": list(sweep.axes),
            "cells": [{"name": r.name, "directory": r.name, "axes": r.axes,
                       **summary_to_dict(r.report.summary, r.report.paired)}
                      for r in reports]}


def sweep_rows(sweep: Sweep, reports: Sequence[CellReport]
               ) -> tuple[tuple[str, ...], list[tuple[str, ...]]]:
    """The sweep's table as text cells: ``(headers, rows)``, a row per cell and method."""
    headers = (*sweep.axes, "method", "trials", "rating (1-5)", "execution time (s)",
               "success rate")
    rows = [(*(r.axes[a] for a in sweep.axes), m.method, str(m.trials), mean_se(m.rating, 2),
             mean_se(m.execution_time_s, 1), rate_text(m.success_rate))
            for r in reports for m in r.report.summary.methods]
    return headers, rows


def sweep_markdown(sweep: Sweep, reports: Sequence[CellReport]) -> str:
    """The sweep's table in Markdown, ending with a newline; each cell's paired
    comparisons are in its own ``summary.md``."""
    headers, rows = sweep_rows(sweep, reports)
    lines = [f"Sweep {sweep.path.name}: {len(reports)} cell(s), mean ± standard error.", "",
             md_row(headers),
             "|" + " --- |" * (len(sweep.axes) + 1) + " ---: |" * 4]
    lines += [md_row(r) for r in rows]
    return "\n".join(lines) + "\n"
