"""The paper's result figures (Sec. IV) drawn from a benchmark :class:`Summary`, as PNG.

* :func:`plot_rating_vs_time` (Fig. 3): one point per method at its mean execution time
  (seconds, x) and mean rating (1-5, y), with standard-error bars on both axes.
* :func:`plot_sweep`: a sweep's cells side by side, rating and execution time per method.
* :func:`plot_rating_per_task` (Fig. 5): grouped bars of the mean rating per task, one
  bar per method, each labelled with its value to one decimal, with standard-error bars;
  each task is labelled with its number of trials per method (``n``).

In the house style of every picture (:mod:`llm_grop.figures`): only matplotlib's object
API and its Agg canvas are used, under a fixed style, at a fixed size and resolution; the
same summary always gives the same PNG bytes. A method or a (method, task) pair without a
value is left out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import matplotlib
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from llm_grop.errors import BadInput
from llm_grop.experiment.summary import Summary
from llm_grop.figures import BACKGROUND, DPI, STYLE, save_png

#: Size (inches) of the rating-vs-time figure (Fig. 3): 900 x 720 pixels at :data:`DPI`.
SCATTER_FIGSIZE_IN = (6.0, 4.8)
#: Size (inches) of the per-task bar figure (Fig. 5): 1650 x 675 pixels at :data:`DPI`.
BARS_FIGSIZE_IN = (11.0, 4.5)
#: Colour and marker of the paper's methods; other methods take :data:`EXTRA_STYLES` in turn.
METHOD_STYLES = {"tpra": ("#1f77b4", "o"), "latp": ("#ff7f0e", "s"),
                 "grop": ("#2ca02c", "^"), "llm-grop": ("#d62728", "D")}
EXTRA_STYLES = (("#9467bd", "v"), ("#8c564b", "P"), ("#e377c2", "X"), ("#7f7f7f", "p"),
                ("#bcbd22", "h"), ("#17becf", "<"))
#: How the paper's methods are named in legends.
DISPLAY_NAMES = {"tpra": "TPRA", "latp": "LATP", "grop": "GROP", "llm-grop": "LLM-GROP"}
GRID_COLOR = "#d9d9d9"
_RATING_MAX = 5.0


def method_styles(methods: tuple[str, ...]) -> dict[str, tuple[str, str]]:
    """``(colour, marker)`` of each of ``methods``: fixed for the paper's, else in turn."""
    extra = [m for m in methods if m not in METHOD_STYLES]
    out = {m: METHOD_STYLES[m] for m in methods if m in METHOD_STYLES}
    out.update({m: EXTRA_STYLES[i % len(EXTRA_STYLES)] for i, m in enumerate(extra)})
    return out


def display_name(method: str) -> str:
    """The legend name of ``method`` (``"LLM-GROP"`` for ``"llm-grop"``)."""
    return DISPLAY_NAMES.get(method, method)


#: Who rated a bench's trials: its summary's ratings come from the automatic rater.
AUTOMATIC = "automatic rating"
#: Who rated a study's pictures (``llm-grop ratings report``): people.
HUMAN = "human rating"


def plot_rating_vs_time(summary: Summary, path: str | Path, *, rated_by: str = AUTOMATIC
                        ) -> None:
    """Write Fig. 3 to ``path``: mean rating (1-5) against mean execution time (s); the
    rating's axis names who rated (``rated_by``: :data:`AUTOMATIC` or :data:`HUMAN`).

    Each method is one marker with standard-error bars on both axes (none when it has a
    single value); a method without a rating or an execution time is not plotted and is
    named in a note under the axes. Raises :class:`BadInput` if ``path`` does not end in
    ``.png`` or cannot be written.
    """
    path = _png_path(path)
    with matplotlib.rc_context(STYLE):
        fig = _new_figure(SCATTER_FIGSIZE_IN)
        # Leave room under the axes for the note naming the methods not shown.
        complete = all(not (math.isnan(m.execution_time_s.mean) or math.isnan(m.rating.mean))
                       for m in summary.methods)
        ax = fig.add_axes((0.12, 0.12, 0.84, 0.82) if complete else (0.12, 0.2, 0.84, 0.74))
        _draw_scatter(ax, summary, rated_by)
        save_png(fig, path)


def plot_rating_per_task(summary: Summary, path: str | Path, *,
                         rated_by: str = AUTOMATIC) -> None:
    """Write Fig. 5 to ``path``: mean rating (0-5 axis) per task as grouped bars, the
    rating's axis naming who rated (``rated_by``).

    Tasks go along x in ascending order, one bar per method in the summary's order, each
    labelled with its mean to one decimal; a (method, task) pair without a rating gets no
    bar. Raises :class:`BadInput` if ``path`` does not end in ``.png`` or cannot be
    written.
    """
    path = _png_path(path)
    with matplotlib.rc_context(STYLE):
        fig = _new_figure(BARS_FIGSIZE_IN)
        ax = fig.add_axes((0.06, 0.17, 0.92, 0.69))
        _draw_bars(ax, summary, rated_by)
        save_png(fig, path)


def _png_path(path: str | Path) -> Path:
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise BadInput(f"image {path}: only PNG pictures are made; use a name ending in .png")
    return path


def _new_figure(size: tuple[float, float]) -> Figure:
    fig = Figure(figsize=size, dpi=DPI, facecolor=BACKGROUND)
    FigureCanvasAgg(fig)
    return fig


def _grid(ax: Axes, axis: str) -> None:
    ax.set_facecolor(BACKGROUND)
    ax.grid(True, axis=axis, color=GRID_COLOR, linewidth=0.6)
    ax.set_axisbelow(True)


def _draw_scatter(ax: Axes, summary: Summary, rated_by: str) -> None:
    _grid(ax, "both")
    styles = method_styles(summary.method_names)
    missing: list[str] = []
    for m in summary.methods:
        x, y = m.execution_time_s, m.rating
        if math.isnan(x.mean) or math.isnan(y.mean):
            missing.append(display_name(m.method))
            continue
        color, marker = styles[m.method]
        ax.errorbar(x.mean, y.mean, xerr=0.0 if math.isnan(x.se) else x.se,
                    yerr=0.0 if math.isnan(y.se) else y.se, fmt=marker, color=color,
                    markersize=8, markeredgecolor="#222222", markeredgewidth=0.6,
                    ecolor=color, elinewidth=1.2, capsize=4, capthick=1.2,
                    label=f"{display_name(m.method)} (n = {y.n})", zorder=3)
    ax.set_xlabel("execution time (s), mean ± SE")
    ax.set_ylabel(f"{rated_by} (1-5), mean ± SE")
    if len(missing) < len(summary.methods):
        ax.margins(x=0.25, y=0.25)
        ax.legend(loc="best", fontsize=8, frameon=True, framealpha=0.9, edgecolor="#cccccc")
    else:
        ax.set_xlim(0.0, 1.0)
        ax.set_ylim(1.0, _RATING_MAX)
        ax.text(0.5, 0.5, "no method has both a rating and an execution time",
                transform=ax.transAxes, ha="center", va="center", color="#666666")
    if missing:
        ax.annotate(f"not shown (no executed trial or no rating): {', '.join(missing)}",
                    xy=(0.0, 0.0), xycoords="axes fraction", xytext=(0, -34),
                    textcoords="offset points", ha="left", va="top", fontsize=8,
                    color="#555555", annotation_clip=False)


def _draw_bars(ax: Axes, summary: Summary, rated_by: str) -> None:
    _grid(ax, "y")
    names = summary.method_names
    tasks = summary.tasks
    styles = method_styles(names)
    width = 0.8 / max(len(names), 1)
    vertical = len(names) > 4  # narrow bars: write the values upwards
    for k, name in enumerate(names):
        xs: list[float] = []
        heights: list[float] = []
        errors: list[float] = []
        for i, task in enumerate(tasks):
            cell = summary.cell(name, task)
            if cell is None or math.isnan(cell.rating.mean):
                continue
            xs.append(i + (k - (len(names) - 1) / 2) * width)
            heights.append(cell.rating.mean)
            errors.append(0.0 if math.isnan(cell.rating.se) else cell.rating.se)
        bars = ax.bar(xs, heights, width=width * 0.92, color=styles[name][0],
                      edgecolor="#333333", linewidth=0.5, label=display_name(name), zorder=2)
        if any(errors):
            ax.errorbar(xs, heights, yerr=errors, fmt="none", ecolor="#222222",
                        elinewidth=0.8, capsize=2.5, capthick=0.8, zorder=3)
        for bar, h, err in zip(bars, heights, errors, strict=True):
            cx = bar.get_x() + bar.get_width() / 2
            # At the bar's foot, clear of its error bar; above a bar too short to hold it.
            inside = h >= (1.2 if vertical else 0.6)
            ax.annotate(f"{h:.1f}", xy=(cx, 0.0 if inside else h + err), xytext=(0, 3),
                        textcoords="offset points", ha="center",
                        va="bottom", rotation=90 if vertical else 0,
                        fontsize=7, color="white" if inside else "#222222",
                        fontweight="bold", zorder=4, annotation_clip=False)
    ax.set_xticks(range(len(tasks)), [f"{t}\n{_n_label(summary, t)}" for t in tasks])
    ax.set_xlim(-0.6, max(len(tasks), 1) - 0.4)
    ax.set_ylim(0.0, _RATING_MAX)
    ax.set_xlabel("task")
    ax.set_ylabel(f"{rated_by} (1-5), mean ± SE")
    if names:
        ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.01), ncol=min(len(names), 6),
                  fontsize=8.5, frameon=False)
    if not tasks:
        ax.text(0.5, 0.5, "no rated trial", transform=ax.transAxes, ha="center",
                va="center", color="#666666")


def _n_label(summary: Summary, task: int) -> str:
    """``n = 20``: the trials behind each bar of ``task`` (``n = 18-20`` when they differ)."""
    counts = sorted({c.rating.n for name in summary.method_names
                     if (c := summary.cell(name, task)) is not None and c.rating.n})
    if not counts:
        return ""
    return f"n = {counts[0]}" if len(counts) == 1 else f"n = {counts[0]}–{counts[-1]}"


#: Inches of the sweep figure's width per cell, its widest (Agg draws at most 2**16
#: pixels a side; beyond it the cells' bars only narrow), and its height (two panels).
SWEEP_IN_PER_CELL = 0.9
SWEEP_MAX_WIDTH_IN = 120.0
SWEEP_HEIGHT_IN = 6.4


def plot_sweep(cells: Sequence[tuple[str, Summary]], path: str | Path) -> None:
    """Write a sweep's figure to ``path``: for each cell (``(label, summary)``, in order),
    one bar per method of its mean rating (1-5, top panel) and mean execution time
    (seconds, bottom panel), with standard-error bars; a cell's label goes under its bars.
    Raises :class:`BadInput` if ``path`` does not end in ``.png`` or cannot be written.
    """
    path = _png_path(path)
    methods = tuple(dict.fromkeys(m for _, s in cells for m in s.method_names))
    styles = method_styles(methods)
    width_in = min(SWEEP_MAX_WIDTH_IN,
                   max(BARS_FIGSIZE_IN[0] * 0.6, 1.5 + SWEEP_IN_PER_CELL * len(cells)))
    with matplotlib.rc_context(STYLE):
        fig = _new_figure((width_in, SWEEP_HEIGHT_IN))
        left = 0.9 / width_in
        rating = fig.add_axes((left, 0.6, 1 - left - 0.2 / width_in, 0.33))
        timing = fig.add_axes((left, 0.22, 1 - left - 0.2 / width_in, 0.33))
        width = 0.8 / max(len(methods), 1)
        for ax, value, unit in ((rating, "rating", "rating (1-5), mean ± SE"),
                                (timing, "execution_time_s", "execution time (s), mean ± SE")):
            _grid(ax, "y")
            for k, name in enumerate(methods):
                xs, heights, errors = [], [], []
                for i, (_, summary) in enumerate(cells):
                    m = summary.method(name)
                    stat_ = getattr(m, value) if m is not None else None
                    if stat_ is None or math.isnan(stat_.mean):
                        continue
                    xs.append(i + (k - (len(methods) - 1) / 2) * width)
                    heights.append(stat_.mean)
                    errors.append(0.0 if math.isnan(stat_.se) else stat_.se)
                ax.bar(xs, heights, width=width * 0.92, color=styles[name][0],
                       edgecolor="#333333", linewidth=0.5, label=display_name(name), zorder=2)
                if any(errors):
                    ax.errorbar(xs, heights, yerr=errors, fmt="none", ecolor="#222222",
                                elinewidth=0.8, capsize=2, capthick=0.8, zorder=3)
            ax.set_xlim(-0.6, max(len(cells), 1) - 0.4)
            ax.set_ylabel(unit)
        rating.set_ylim(0.0, _RATING_MAX)
        rating.set_xticks(range(len(cells)), [""] * len(cells))
        timing.set_xticks(range(len(cells)), [label.replace(",", "\n") for label, _ in cells],
                          fontsize=7)
        if methods:
            rating.legend(loc="lower center", bbox_to_anchor=(0.5, 1.01),
                          ncol=min(len(methods), 6), fontsize=8.5, frameon=False)
        save_png(fig, path)
