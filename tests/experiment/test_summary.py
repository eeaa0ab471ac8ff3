"""Summaries of benchmark rows: means, standard errors, ordering and their tables."""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any

import pytest
from rich.console import Console

from llm_grop.errors import BadInput
from llm_grop.experiment.summary import (
    PAPER_ORDER,
    Stat,
    print_summary,
    stat,
    summarize,
    summary_markdown,
    summary_to_dict,
)
from rows import trial_row


def row(method: str, task: int, rating: int, execution: float | None,
        planning: float | None = 0.01, success: bool = True, trial: int = 0) -> dict[str, Any]:
    return trial_row(method, task, rating, execution, planning, success, trial)


ROWS = [
    row("mine", 3, 4, 70.0),
    row("llm-grop", 1, 5, 50.0, planning=0.020),
    row("llm-grop", 1, 4, 60.0, planning=0.030, trial=1),
    row("llm-grop", 2, 3, None, planning=None, success=False, trial=2),
    row("tpra", 2, 2, 100.0, success=False),
    row("tpra", 1, 4, 120.0, trial=1),
    row("other", 1, 1, None, success=False),
    row("grop", 2, 3, 80.0),
]


def test_stat_mean_and_standard_error() -> None:
    s = stat([2, 4])
    assert s.n == 2
    assert s.mean == pytest.approx(3.0)
    assert s.se == pytest.approx(1.0)  # sd sqrt(2), over sqrt(2)
    s = stat([5.0, 4.0, 3.0])
    assert s.mean == pytest.approx(4.0)
    assert s.se == pytest.approx(1.0 / math.sqrt(3.0))


def test_stat_ignores_none_and_handles_small_samples() -> None:
    assert stat([None, 3.0, None, 5.0]) == stat([3.0, 5.0])
    one = stat([None, 2.5])
    assert (one.mean, one.n) == (2.5, 1) and math.isnan(one.se)
    empty = stat([None, None])
    assert empty.n == 0 and math.isnan(empty.mean) and math.isnan(empty.se)
    assert stat([]).n == 0
    booleans = stat([True, False, True, True])
    assert booleans.mean == pytest.approx(0.75)


def test_methods_paper_order_then_first_seen() -> None:
    summary = summarize(ROWS)
    assert summary.method_names == ("tpra", "grop", "llm-grop", "mine", "other")
    assert PAPER_ORDER == ("tpra", "latp", "grop", "llm-grop")
    assert summary.tasks == (1, 2, 3)
    assert [(t.method, t.task) for t in summary.per_task] == [
        ("tpra", 1), ("tpra", 2), ("grop", 2), ("llm-grop", 1), ("llm-grop", 2),
        ("mine", 3), ("other", 1)]


def test_per_method_statistics() -> None:
    summary = summarize(ROWS)
    tpra = summary.method("tpra")
    assert tpra is not None and tpra.trials == 2
    assert tpra.rating.mean == pytest.approx(3.0) and tpra.rating.se == pytest.approx(1.0)
    assert tpra.execution_time_s.mean == pytest.approx(110.0)
    assert tpra.execution_time_s.se == pytest.approx(10.0)
    assert tpra.success_rate == Stat(0.5, pytest.approx(0.5), 2)  # type: ignore[arg-type]

    llm = summary.method("llm-grop")
    assert llm is not None and llm.trials == 3
    assert llm.rating.mean == pytest.approx(4.0)
    assert llm.rating.se == pytest.approx(1.0 / math.sqrt(3.0))
    # The infeasible trial has no execution or planning time: left out, not counted as 0.
    assert llm.execution_time_s.n == 2 and llm.execution_time_s.mean == pytest.approx(55.0)
    assert llm.execution_time_s.se == pytest.approx(5.0)
    assert llm.planning_time_s.n == 2 and llm.planning_time_s.mean == pytest.approx(0.025)
    assert llm.success_rate.mean == pytest.approx(2 / 3)

    other = summary.method("other")
    assert other is not None and other.execution_time_s.n == 0
    assert math.isnan(other.execution_time_s.mean)
    assert summary.method("latp") is None


def test_per_task_statistics() -> None:
    summary = summarize(ROWS)
    cell = summary.cell("llm-grop", 1)
    assert cell is not None
    assert cell.rating.mean == pytest.approx(4.5) and cell.rating.se == pytest.approx(0.5)
    assert cell.execution_time_s.mean == pytest.approx(55.0)
    two = summary.cell("llm-grop", 2)
    assert two is not None and two.rating == Stat(3.0, two.rating.se, 1)
    assert two.execution_time_s.n == 0
    assert summary.cell("grop", 1) is None
    table = summary.task_table()
    assert table[("tpra", 2)][0].mean == pytest.approx(2.0)
    assert table[("tpra", 2)][1].mean == pytest.approx(100.0)


def test_summary_is_immutable_and_hashable() -> None:
    summary = summarize(ROWS)
    with pytest.raises(dataclasses.FrozenInstanceError):
        summary.methods = ()  # type: ignore[misc]
    assert isinstance(hash(summary), int)
    assert summarize(iter(ROWS)) == summary


def test_empty_input() -> None:
    summary = summarize([])
    assert summary.methods == () and summary.per_task == () and summary.tasks == ()
    assert "| method |" in summary_markdown(summary)


@pytest.mark.parametrize(("change", "message"), [
    ({"method": ""}, "method"),
    ({"task": "1"}, "task"),
    ({"task": True}, "task"),
    ({"success": 1}, "success"),
    ({"rating": 6}, "rating"),
    ({"rating": "good"}, "rating"),
    ({"execution_time_s": -1.0}, "execution_time_s"),
    ({"planning_time_s": float("nan")}, "planning_time_s"),
])
def test_bad_rows_are_rejected(change: dict[str, Any], message: str) -> None:
    bad = {**row("grop", 1, 3, 10.0), **change}
    with pytest.raises(BadInput, match=rf"benchmark row 2: .*{message}"):
        summarize([row("grop", 1, 3, 10.0), bad])


def test_missing_field_is_named() -> None:
    bad = row("grop", 1, 3, 10.0)
    del bad["rating"]
    with pytest.raises(BadInput, match="row 1: rating: required, but missing"):
        summarize([bad])


def test_summary_to_dict_is_json_ready() -> None:
    data = summary_to_dict(summarize(ROWS))
    text = json.dumps(data, allow_nan=False)  # NaN became null
    back = json.loads(text)
    assert [m["method"] for m in back["methods"]] == ["tpra", "grop", "llm-grop", "mine",
                                                      "other"]
    tpra = back["methods"][0]
    assert tpra["trials"] == 2
    assert tpra["rating"] == {"mean": pytest.approx(3.0), "se": pytest.approx(1.0), "n": 2}
    assert back["methods"][4]["execution_time_s"] == {"mean": None, "se": None, "n": 0}
    assert back["tasks"] == [1, 2, 3]
    assert {"method": "grop", "task": 2, "rating": {"mean": 3.0, "se": None, "n": 1},
            "execution_time_s": {"mean": 80.0, "se": None, "n": 1}} in back["per_task"]


def test_markdown_tables_hold_the_numbers() -> None:
    text = summary_markdown(summarize(ROWS))
    lines = text.splitlines()
    assert lines[0].startswith("| method |") and "execution time (s)" in lines[0]
    assert "planning time (ms)" in lines[0]
    tpra = next(line for line in lines if line.startswith("| tpra |"))
    assert "| 2 |" in tpra
    assert "3.00 ± 1.00" in tpra and "110.0 ± 10.0" in tpra and "50% (1/2)" in tpra
    assert "10.0 ± 0.0" in tpra  # planning 0.01 s twice: 10 ms
    llm = next(line for line in lines if line.startswith("| llm-grop |"))
    assert "4.00 ± 0.58" in llm and "55.0 ± 5.0" in llm and "67% (2/3)" in llm
    assert "25.0 ± 5.0" in llm
    other = next(line for line in lines if line.startswith("| other |"))
    assert other.split("|")[4].strip() == "-"  # no execution time at all
    grop = next(line for line in lines if line.startswith("| grop |"))
    assert "| 3.00 |" in grop  # one rating: no SE
    # Per-task table: columns are the methods, rows the tasks.
    header = lines.index("| task | tpra | grop | llm-grop | mine | other |")
    assert lines[header + 2] == "| 1 | 4.00 | - | 4.50 | - | 1.00 |"
    assert lines[header + 3] == "| 2 | 2.00 | 3.00 | 3.00 | - | - |"
    assert lines[header + 4] == "| 3 | - | - | - | 4.00 | - |"
    assert text.endswith("\n")


def test_markdown_escapes_pipes_in_names() -> None:
    text = summary_markdown(summarize([row("a|b", 1, 3, 1.0)]))
    assert "| a\\|b |" in text


def test_print_summary_shows_both_tables() -> None:
    console = Console(record=True, width=200, color_system=None)
    print_summary(summarize(ROWS + [row("[bold]x", 1, 2, 3.0)]), console)
    out = console.export_text()
    assert "Results per method" in out and "Mean rating (1-5) per task" in out
    assert "3.00 ± 1.00" in out and "110.0 ± 10.0" in out and "67% (2/3)" in out
    assert "llm-grop" in out and "4.50" in out
    assert "[bold]x" in out  # markup in a method name is shown, not interpreted
