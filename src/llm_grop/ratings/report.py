"""The human ratings' report: the paper's figures of merit from people, not the rater.

A picture's human rating is the mean of its raters' 1-5 ratings; statistics are over
pictures (trials), so the standard error counts trials, not ratings. The report holds:

* mean ± standard error per method, and per task and method (as the bench's summary);
* inter-rater agreement: Krippendorff's alpha, ordinal (the ``krippendorff`` package);
* humans against the automatic rater: Spearman's rho (scipy) between a picture's human
  mean and its automatic rating, Krippendorff's ordinal alpha between the automatic
  rating and the rounded human median, and how often a single human rating equals it;
* paired comparisons of methods on the same trials (Wilcoxon signed-rank,
  :mod:`llm_grop.experiment.paired`);
* Fig. 3 and Fig. 5 from the human ratings, by the bench's own plotting code.

A table shows only the columns that hold a figure: one whose every cell is empty (the
planning time, which a study does not keep) is left out.
"""

from __future__ import annotations

import math
import sqlite3
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from statistics import mean, median
from typing import Any

import krippendorff
import numpy as np
from scipy import stats

from llm_grop.experiment.paired import PairedComparison, paired_comparisons
from llm_grop.experiment.plots import HUMAN, plot_rating_per_task, plot_rating_vs_time
from llm_grop.experiment.summary import (
    Summary,
    Table,
    md_row,
    summarize_outcomes,
    summary_tables,
    summary_to_dict,
)
from llm_grop.files.jsonio import write_json, write_text
from llm_grop.ratings.pages import STATIC, render

FIG3 = "fig3_rating_vs_time.png"
FIG5 = "fig5_rating_per_task.png"
#: The files :func:`write_report` writes into its directory.
FILES = ("report.json", "report.md", "report.html", FIG3, FIG5)
#: What a table's cell holds when it has no figure.
EMPTY = ("", "-")


@dataclass(frozen=True)
class RatedTrial:
    """One picture with its ratings: ``rating`` is the mean of ``ratings`` (1-5)."""

    method: str
    task: int
    trial: int
    ratings: tuple[int, ...]
    automatic_rating: int
    execution_time_s: float | None
    success: bool
    planning_time_s: float | None = None

    @property
    def rating(self) -> float:
        """The mean human rating (1-5)."""
        return mean(self.ratings)


@dataclass(frozen=True)
class Agreement:
    """How far two sets of ratings agree; NaN where a figure cannot be computed."""

    alpha: float
    spearman: float
    exact: float
    within_one: float
    n: int


@dataclass(frozen=True)
class HumanReport:
    """What the people said about the study's pictures."""

    study: str
    pictures: int
    raters: int
    ratings: int
    summary: Summary
    inter_rater_alpha: float
    automatic: Agreement
    paired: tuple[PairedComparison, ...]


def read_trials(conn: sqlite3.Connection) -> tuple[str, int, list[RatedTrial]]:
    """``(study name, pictures, rated pictures)`` from a study database."""
    ratings: dict[str, list[int]] = defaultdict(list)
    for row in conn.execute("SELECT item_id, rating FROM ratings ORDER BY rater_id"):
        ratings[row[0]].append(row[1])
    study = conn.execute("SELECT name FROM study").fetchone()
    items = conn.execute("SELECT id, method, task, trial, automatic_rating, execution_time_s,"
                         " success FROM items ORDER BY position").fetchall()
    rated = [RatedTrial(r["method"], r["task"], r["trial"], tuple(ratings[r["id"]]),
                        r["automatic_rating"], r["execution_time_s"], bool(r["success"]))
             for r in items if ratings[r["id"]]]
    return (study["name"] if study else ""), len(items), rated


def _alpha(matrix: list[list[float]]) -> float:
    """Krippendorff's ordinal alpha of coders x units (NaN = not rated); NaN when there is
    too little to compute it (fewer than two coders on a unit, or one value only)."""
    data = np.asarray(matrix, dtype=float)
    pairable = (np.sum(~np.isnan(data), axis=0) >= 2).sum() if data.size else 0
    values = np.unique(data[~np.isnan(data)]) if data.size else []
    if data.shape[0] < 2 or pairable == 0 or len(values) < 2:
        return math.nan
    return float(krippendorff.alpha(reliability_data=data, level_of_measurement="ordinal",
                                    value_domain=[1, 2, 3, 4, 5]))


def human_report(conn: sqlite3.Connection) -> HumanReport:
    """The report of the study in ``conn``."""
    study, pictures, trials = read_trials(conn)
    raters = [r[0] for r in conn.execute("SELECT DISTINCT rater_id FROM ratings ORDER BY 1")]
    items = [r[0] for r in conn.execute("SELECT id FROM items ORDER BY position")]
    column = {item: k for k, item in enumerate(items)}
    row_of = {rater: k for k, rater in enumerate(raters)}
    matrix = [[math.nan] * len(items) for _ in raters]
    for rater, item, value in conn.execute("SELECT rater_id, item_id, rating FROM ratings"):
        matrix[row_of[rater]][column[item]] = value
    summary = summarize_outcomes(trials)
    by_method: dict[str, dict[tuple[int, int], float]] = defaultdict(dict)
    for t in trials:
        by_method[t.method][(t.task, t.trial)] = t.rating
    return HumanReport(
        study=study, pictures=pictures, raters=len(raters),
        ratings=sum(len(t.ratings) for t in trials), summary=summary,
        inter_rater_alpha=_alpha(matrix), automatic=_automatic(trials),
        paired=paired_comparisons(by_method, summary.method_names))


def _automatic(trials: list[RatedTrial]) -> Agreement:
    if not trials:
        return Agreement(math.nan, math.nan, math.nan, math.nan, 0)
    auto = [t.automatic_rating for t in trials]
    human = [t.rating for t in trials]
    singles = [(h, t.automatic_rating) for t in trials for h in t.ratings]
    rho = math.nan
    if len(set(auto)) > 1 and len(set(human)) > 1:
        rho = float(stats.spearmanr(human, auto).statistic)
    medians = [float(round(median(t.ratings) + 1e-9)) for t in trials]
    return Agreement(alpha=_alpha([auto, medians]), spearman=rho,
                     exact=sum(h == a for h, a in singles) / len(singles),
                     within_one=sum(abs(h - a) <= 1 for h, a in singles) / len(singles),
                     n=len(trials))


def _num(x: float) -> float | None:
    return None if math.isnan(x) else round(x, 4)


def report_to_dict(report: HumanReport) -> dict[str, Any]:
    """``report`` as plain JSON values; NaN becomes ``None``."""
    a = report.automatic
    return {"study": report.study, "pictures": report.pictures, "raters": report.raters,
            "ratings": report.ratings, "summary": summary_to_dict(report.summary),
            "inter_rater_alpha_ordinal": _num(report.inter_rater_alpha),
            "automatic_rater": {"alpha_ordinal": _num(a.alpha), "spearman_rho": _num(a.spearman),
                                "exact_agreement": _num(a.exact),
                                "within_one": _num(a.within_one), "pictures": a.n},
            "paired": [p.to_json() for p in report.paired]}


def counted(n: int, noun: str) -> str:
    """``n`` and ``noun``, plural unless ``n`` is 1 ("1 picture", "3 methods")."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _fmt(x: float, digits: int = 3) -> str:
    return "-" if math.isnan(x) else f"{x:.{digits}f}"


def with_data(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> Table:
    """The table ``(headers, rows)`` without the columns whose every cell is empty
    (:data:`EMPTY`); a table without rows keeps them all."""
    keep = [k for k in range(len(headers))
            if not rows or any(str(r[k]).strip() not in EMPTY for r in rows)]
    return tuple(headers[k] for k in keep), [tuple(r[k] for k in keep) for r in rows]


def sections(report: HumanReport) -> dict[str, Any]:
    """The report's figures as text, for the Markdown and the HTML page alike: its tables
    (``tables``: per method, per task, and the paired comparisons) hold only the columns
    with data."""
    a = report.automatic
    per_method, per_task = summary_tables(report.summary, with_se=True)
    paired = with_data(
        ("first", "second", "shared trials", "mean difference (first - second)",
         "95 % bootstrap CI", "Wilcoxon W", "p", "rank-biserial r"),
        [(p.first, p.second, str(p.n), _fmt(p.mean_difference, 2),
          "-" if math.isnan(p.ci_low) else f"[{_fmt(p.ci_low, 2)}, {_fmt(p.ci_high, 2)}]",
          _fmt(p.statistic, 1), _fmt(p.p_value, 4), _fmt(p.effect_size, 2))
         for p in report.paired])
    return {
        "headline": f"{counted(report.ratings, 'rating')} of "
                    f"{sum(m.trials for m in report.summary.methods)} of the "
                    f"{counted(report.pictures, 'picture')} by {counted(report.raters, 'rater')}",
        "agreement": [
            ("Krippendorff's alpha (ordinal) between raters", _fmt(report.inter_rater_alpha)),
            ("Krippendorff's alpha (ordinal), automatic rater vs human median",
             _fmt(a.alpha)),
            ("Spearman's rho, automatic rater vs human mean", _fmt(a.spearman)),
            ("single human ratings equal to the automatic rating", _fmt(a.exact, 2)),
            ("single human ratings within 1 of the automatic rating", _fmt(a.within_one, 2))],
        "per_method": with_data(*per_method), "per_task": with_data(*per_task),
        "paired_header": paired[0], "paired": paired[1],
    }


def _md_table(table: Table, left: int) -> list[str]:
    """``table`` as Markdown lines, its first ``left`` columns left-aligned."""
    headers, rows = table
    align = ["---" if k < left else "---:" for k in range(len(headers))]
    return [md_row(headers), md_row(align), *(md_row(r) for r in rows)]


def report_markdown(report: HumanReport) -> str:
    """The report as Markdown, ending with a newline."""
    s = sections(report)
    lines = [f"# Human ratings: {report.study}", "", s["headline"] + ".", "",
             "Mean human rating per picture (1-5), then over pictures:", "",
             *_md_table(s["per_method"], left=1), "",
             "Mean rating (1-5) per task, ± SE:", "", *_md_table(s["per_task"], left=0), "",
             "## Agreement", "",
             "| figure | value |", "| --- | ---: |"]
    lines += [f"| {k} | {v} |" for k, v in s["agreement"]]
    lines += ["", "## Paired comparisons (same task and trial)", "",
              *_md_table((s["paired_header"], s["paired"]), left=2)]
    lines += ["", f"![Fig. 3]({FIG3})", "", f"![Fig. 5]({FIG5})"]
    return "\n".join(lines) + "\n"


def write_report(report: HumanReport, out: Path) -> list[Path]:
    """Write :data:`FILES` into the directory ``out`` (made if missing); their paths."""
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "report.json", report_to_dict(report))
    plot_rating_vs_time(report.summary, out / FIG3, rated_by=HUMAN)
    plot_rating_per_task(report.summary, out / FIG5, rated_by=HUMAN)
    write_text(out / "report.md", report_markdown(report))
    write_text(out / "report.html", render(
        "report.html", report=report, s=sections(report), fig3=FIG3, fig5=FIG5,
        stylesheet=(STATIC / "style.css").read_text("utf-8")))
    return [out / name for name in FILES]

