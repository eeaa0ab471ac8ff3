"""Aggregate benchmark trials into the paper's figures of merit (Sec. IV).

The benchmark writes one :class:`~llm_grop.contract.models.TrialRow` per trial: among
others ``method``, ``task``, ``success``, ``rating`` (1-5), ``execution_time_s`` (seconds,
``None`` when no plan existed) and ``planning_time_s`` (seconds, or ``None``).
:func:`summarize` reduces them to means and standard errors per method (Fig. 3: rating
against execution time) and per method and task (Fig. 5: mean rating per task).
Standard errors are the sample standard deviation (``n - 1`` in the denominator)
divided by ``sqrt(n)``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from rich.console import Console
from rich.markup import escape
from rich.table import Table as RichTable

from llm_grop.contract.models import TrialRow
from llm_grop.contract.serialize import read_doc
from llm_grop.experiment.paired import PairedComparison

#: The paper's methods, in the order its figures list them; others follow, first seen first.
PAPER_ORDER = ("tpra", "latp", "grop", "llm-grop")

_NONE = "-"


@dataclass(frozen=True)
class Stat:
    """Mean and standard error of ``n`` values, in the values' own unit.

    ``mean`` is NaN when ``n == 0``; ``se`` (sample standard deviation / sqrt(n)) is
    NaN when ``n < 2``.
    """

    mean: float
    se: float
    n: int


def stat(values: Iterable[float | int | bool | None]) -> Stat:
    """The :class:`Stat` of ``values``, ignoring ``None`` (booleans count as 0 or 1)."""
    xs = [float(v) for v in values if v is not None]
    n = len(xs)
    if n == 0:
        return Stat(math.nan, math.nan, 0)
    mean = math.fsum(xs) / n
    if n < 2:
        return Stat(mean, math.nan, n)
    var = math.fsum((x - mean) ** 2 for x in xs) / (n - 1)
    return Stat(mean, math.sqrt(var) / math.sqrt(n), n)


@dataclass(frozen=True)
class MethodSummary:
    """All trials of one method.

    ``rating`` is on the 1-5 scale; ``execution_time_s`` and ``planning_time_s`` are in
    seconds, over the trials that have them; ``success_rate`` is the mean of 0/1 success
    (a fraction, 0-1); ``trials`` counts every row of the method.
    """

    method: str
    rating: Stat
    execution_time_s: Stat
    planning_time_s: Stat
    success_rate: Stat
    trials: int


@dataclass(frozen=True)
class TaskSummary:
    """The trials of one method on one task: ``rating`` (1-5), ``execution_time_s`` (s)."""

    method: str
    task: int
    rating: Stat
    execution_time_s: Stat


@dataclass(frozen=True)
class Summary:
    """Per-method results (``methods``, in display order) and per-(method, task) results.

    ``per_task`` holds one :class:`TaskSummary` for each (method, task) pair that has
    trials, ordered by method (as in ``methods``) then by task ascending.
    """

    methods: tuple[MethodSummary, ...]
    per_task: tuple[TaskSummary, ...]
    #: Trials whose LLM failed after its retries, per method: left out of every figure.
    llm_failed: tuple[tuple[str, int], ...] = ()

    @property
    def method_names(self) -> tuple[str, ...]:
        """The methods, in display order."""
        return tuple(m.method for m in self.methods)

    @property
    def tasks(self) -> tuple[int, ...]:
        """Every task that has a trial, ascending."""
        return tuple(sorted({t.task for t in self.per_task}))

    def method(self, name: str) -> MethodSummary | None:
        """The summary of method ``name``, or ``None`` if it has no trial."""
        return next((m for m in self.methods if m.method == name), None)

    def cell(self, method: str, task: int) -> TaskSummary | None:
        """The results of ``method`` on ``task``, or ``None`` if it has no trial there."""
        return next((t for t in self.per_task if t.method == method and t.task == task), None)

    def task_table(self) -> dict[tuple[str, int], tuple[Stat, Stat]]:
        """A fresh ``{(method, task): (rating, execution_time_s)}`` mapping."""
        return {(t.method, t.task): (t.rating, t.execution_time_s) for t in self.per_task}


def summarize(rows: Iterable[TrialRow | Mapping[str, Any]]) -> Summary:
    """Summarize trial rows (one per trial) per method and per (method, task).

    Methods come in the paper's order (:data:`PAPER_ORDER`) first, then any others in the
    order first seen; tasks ascending. ``None`` times are left out of their statistics.
    A row given as a mapping is validated as a :class:`TrialRow`; a malformed one raises
    :class:`BadInput` naming the row, counted from 1, and the field.
    """
    return summarize_outcomes([
        r if isinstance(r, TrialRow) else read_doc(TrialRow, r, f"benchmark row {i}")
        for i, r in enumerate(rows, 1)])


class Outcome(Protocol):
    """What a summary needs of one trial: a :class:`TrialRow` has it, and so has a trial
    rated by people (``rating`` then the mean of their 1-5 ratings)."""

    @property
    def method(self) -> str: ...
    @property
    def task(self) -> int: ...
    @property
    def rating(self) -> float: ...
    @property
    def execution_time_s(self) -> float | None: ...
    @property
    def planning_time_s(self) -> float | None: ...
    @property
    def success(self) -> bool: ...


def summarize_outcomes(parsed: Sequence[Outcome]) -> Summary:
    """:func:`summarize` of trials already read; trials whose LLM failed (``status``
    ``llm-failed``) are counted apart and left out of every statistic."""
    failed: dict[str, int] = {}
    for r in parsed:
        if getattr(r, "status", "ok") == "llm-failed":
            failed[r.method] = failed.get(r.method, 0) + 1
    parsed = [r for r in parsed if getattr(r, "status", "ok") != "llm-failed"]
    seen: dict[str, None] = {}
    for r in parsed:
        seen.setdefault(r.method, None)
    order = [m for m in PAPER_ORDER if m in seen] + [m for m in seen if m not in PAPER_ORDER]
    methods: list[MethodSummary] = []
    per_task: list[TaskSummary] = []
    for name in order:
        mine = [r for r in parsed if r.method == name]
        methods.append(MethodSummary(
            method=name,
            rating=stat(r.rating for r in mine),
            execution_time_s=stat(r.execution_time_s for r in mine),
            planning_time_s=stat(r.planning_time_s for r in mine),
            success_rate=stat(r.success for r in mine),
            trials=len(mine)))
        for task in sorted({r.task for r in mine}):
            on_task = [r for r in mine if r.task == task]
            per_task.append(TaskSummary(name, task, stat(r.rating for r in on_task),
                                        stat(r.execution_time_s for r in on_task)))
    return Summary(tuple(methods), tuple(per_task), tuple(failed.items()))


def _stat_dict(s: Stat) -> dict[str, float | int | None]:
    return {"mean": None if math.isnan(s.mean) else s.mean,
            "se": None if math.isnan(s.se) else s.se, "n": s.n}


Paired = Mapping[str, Sequence[PairedComparison]]


def summary_to_dict(summary: Summary, paired: Paired | None = None) -> dict[str, Any]:
    """``summary`` as plain JSON values; NaN (no value, or no SE) becomes ``None``.

    Times stay in seconds (keys ending in ``_s``); ``success_rate`` is a fraction (0-1).
    ``paired`` (value name -> comparisons, :func:`~llm_grop.experiment.paired.paired_by_trial`)
    is added under ``"paired"`` when given.
    """
    extra = {} if paired is None else {"paired": {
        value: [c.to_json() for c in comparisons] for value, comparisons in paired.items()}}
    return {
        "methods": [{"method": m.method, "trials": m.trials,
                     "rating": _stat_dict(m.rating),
                     "execution_time_s": _stat_dict(m.execution_time_s),
                     "planning_time_s": _stat_dict(m.planning_time_s),
                     "success_rate": _stat_dict(m.success_rate)} for m in summary.methods],
        "tasks": list(summary.tasks),
        **({"llm_failed": dict(summary.llm_failed)} if summary.llm_failed else {}),
        "per_task": [{"method": t.method, "task": t.task, "rating": _stat_dict(t.rating),
                      "execution_time_s": _stat_dict(t.execution_time_s)}
                     for t in summary.per_task],
    } | extra


def mean_se(s: Stat, digits: int, scale: float = 1.0) -> str:
    """``"mean ± se"`` (``scale`` times each) to ``digits`` decimals; just the mean when
    there is no SE; ``"-"`` when there is no value."""
    if math.isnan(s.mean):
        return _NONE
    text = f"{s.mean * scale:.{digits}f}"
    return text if math.isnan(s.se) else f"{text} ± {s.se * scale:.{digits}f}"


def rate_text(s: Stat) -> str:
    """A success rate as ``"90% (18/20)"``."""
    if s.n == 0:
        return _NONE
    return f"{s.mean * 100:.0f}% ({round(s.mean * s.n)}/{s.n})"


_METHOD_HEADERS = ("method", "trials", "rating (1-5), mean ± SE",
                   "execution time (s), mean ± SE", "success rate",
                   "planning time (ms), mean ± SE")


def _method_cells(m: MethodSummary) -> tuple[str, ...]:
    return (m.method, str(m.trials), mean_se(m.rating, 2), mean_se(m.execution_time_s, 1),
            rate_text(m.success_rate), mean_se(m.planning_time_s, 1, scale=1000.0))


def _task_cells(summary: Summary, task: int, with_se: bool) -> tuple[str, ...]:
    cells = [str(task)]
    for name in summary.method_names:
        c = summary.cell(name, task)
        cells.append(_NONE if c is None else mean_se(c.rating, 2) if with_se
                     else mean_se(Stat(c.rating.mean, math.nan, c.rating.n), 2))
    return tuple(cells)


def md_row(cells: Iterable[str]) -> str:
    return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"


Table = tuple[tuple[str, ...], list[tuple[str, ...]]]


def summary_tables(summary: Summary, *, with_se: bool = False) -> tuple[Table, Table]:
    """The two tables of :func:`summary_markdown` as text cells: ``(headers, rows)`` per
    method, then per task (each mean ``± SE`` too when ``with_se``)."""
    return ((_METHOD_HEADERS, [_method_cells(m) for m in summary.methods]),
            (("task", *summary.method_names),
             [_task_cells(summary, task, with_se) for task in summary.tasks]))


def _task_title(with_se: bool) -> str:
    return "Mean rating (1-5) per task" + (", ± SE" if with_se else "")


def summary_markdown(summary: Summary, *, with_se: bool = False,
                     paired: Paired | None = None) -> str:
    """Two Markdown tables: per method (rating, execution time in s, success rate,
    planning time in ms, each mean ± standard error) and mean rating per task (rows:
    tasks; columns: methods; ``± SE`` when ``with_se``); then, when ``paired`` is given,
    the paired comparisons of :func:`paired_table`. Ends with a newline."""
    (headers, rows), (task_headers, task_rows) = summary_tables(summary, with_se=with_se)
    lines = [md_row(headers), "| --- | ---: | ---: | ---: | ---: | ---: |"]
    lines += [md_row(r) for r in rows]
    lines += ["", f"{_task_title(with_se)}:", "", md_row(task_headers),
              "| ---: |" + " ---: |" * (len(task_headers) - 1)]
    lines += [md_row(r) for r in task_rows]
    if paired:
        headers, rows = paired_table(paired)
        lines += ["", f"{PAIRED_TITLE}:", "", md_row(headers),
                  "| --- | --- | --- |" + " ---: |" * (len(headers) - 3)]
        lines += [md_row(r) for r in rows]
    if summary.llm_failed:
        n = sum(k for _, k in summary.llm_failed)
        each = ", ".join(f"{m} {k}" for m, k in summary.llm_failed)
        lines += ["", f"Left out: {n} trial(s) whose LLM failed after its retries ({each}); "
                      "rerun the same command to retry them."]
    return "\n".join(lines) + "\n"


PAIRED_TITLE = ("Paired comparisons on the same task and trial: the mean difference first - "
                "second with its 95 % bootstrap CI, Wilcoxon signed-rank W and p, "
                "rank-biserial r")
_PAIRED_HEADERS = ("value", "first", "second", "n", "mean diff.", "95 % CI", "W", "p", "r")
_VALUE_NAMES = {"rating": "rating", "execution_time_s": "time (s)"}


def paired_table(paired: Paired) -> Table:
    """The paired comparisons as text cells: ``(headers, rows)``, one row per value and
    pair of methods."""
    def num(x: float, digits: int) -> str:
        return _NONE if math.isnan(x) else f"{x:.{digits}f}"

    rows = []
    for value, comparisons in paired.items():
        digits = 2 if value == "rating" else 1
        for c in comparisons:
            ci = _NONE if math.isnan(c.ci_low) else \
                f"[{c.ci_low:.{digits}f}, {c.ci_high:.{digits}f}]"
            rows.append((_VALUE_NAMES.get(value, value), c.first, c.second, str(c.n),
                         num(c.mean_difference, digits), ci, num(c.statistic, 1),
                         _p(c.p_value), num(c.effect_size, 2)))
    return _PAIRED_HEADERS, rows


def _p(p: float) -> str:
    """A p-value: 4 decimals, or ``< 0.0001``."""
    if math.isnan(p):
        return _NONE
    return "< 0.0001" if p < 1e-4 else f"{p:.4f}"


def rich_table(title: str, headers: Sequence[str], rows: Iterable[Sequence[str]],
               left: int = 1) -> RichTable:
    """A rich table of text cells, its first ``left`` columns left-aligned, the others
    (numbers) right-aligned; every cell is printed as it is, never read as markup."""
    table = RichTable(title=title, title_justify="left")
    for k, header in enumerate(headers):
        table.add_column(escape(header), justify="left" if k < left else "right")
    for row in rows:
        table.add_row(*(escape(c) for c in row))
    return table


def print_summary(summary: Summary, console: Console, *, with_se: bool = False,
                  paired: Paired | None = None) -> None:
    """Print the tables of :func:`summary_markdown` to ``console`` as rich tables."""
    (headers, rows), (task_headers, task_rows) = summary_tables(summary, with_se=with_se)
    console.print(rich_table("Results per method (mean ± standard error)", headers, rows))
    console.print(rich_table(_task_title(with_se), task_headers, task_rows, left=0))
    if paired:
        console.print(rich_table(PAIRED_TITLE, *paired_table(paired), left=3))
    if summary.llm_failed:
        n = sum(k for _, k in summary.llm_failed)
        console.print(f"[yellow]{n} trial(s) got no usable LLM answer after their retries and are "
                      "left out; rerun the same command to retry them[/yellow]")
