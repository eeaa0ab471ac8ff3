"""The human ratings' report against hand computation, scipy and krippendorff."""

from __future__ import annotations

import json
import math
import sqlite3
from pathlib import Path
from statistics import mean, stdev

import krippendorff
import numpy as np
import pytest
from scipy import stats

from llm_grop.experiment.paired import compare
from llm_grop.ratings.db import connect
from llm_grop.ratings.report import FILES, human_report, write_report
from llm_grop.ratings.store import RatingStore


def rate_all(db: Path, rule) -> dict[tuple[int, str], int]:
    """Every rater rates every picture ``rule(rater number, item row)``; the ratings."""
    conn = connect(db)
    given = {}
    try:
        store = RatingStore(conn)
        items = conn.execute("SELECT id, task, trial, method, automatic_rating FROM items"
                             " ORDER BY position").fetchall()
        for rater in (1, 2, 3):
            for item in items:
                value = rule(rater, item)
                store.rate(rater, item["id"], value)
                given[(rater, item["id"])] = value
    finally:
        conn.close()
    return given


def rule(rater: int, item) -> int:
    """Ratings that depend on the method, the trial and the rater (so raters disagree a bit)."""
    base = {"tpra": 2, "latp": 3, "grop": 3, "llm-grop": 4}[item["method"]]
    return max(1, min(5, base + (item["trial"] + rater) % 3 - 1))


def test_report_matches_hand_computation(study) -> None:
    db, _ = study
    given = rate_all(db, rule)
    conn = connect(db)
    try:
        report = human_report(conn)
        items = conn.execute("SELECT id, task, trial, method, automatic_rating FROM items"
                             " ORDER BY position").fetchall()
    finally:
        conn.close()
    assert (report.pictures, report.raters, report.ratings) == (16, 3, 48)
    per_picture = {i["id"]: mean(given[(r, i["id"])] for r in (1, 2, 3)) for i in items}
    for m in report.summary.methods:
        values = [per_picture[i["id"]] for i in items if i["method"] == m.method]
        assert m.rating.n == 4
        assert m.rating.mean == pytest.approx(mean(values))
        assert m.rating.se == pytest.approx(stdev(values) / math.sqrt(4))
    cell = report.summary.cell("llm-grop", 2)
    assert cell is not None and cell.rating.mean == pytest.approx(mean(
        per_picture[i["id"]] for i in items if i["method"] == "llm-grop" and i["task"] == 2))
    matrix = np.array([[given[(r, i["id"])] for i in items] for r in (1, 2, 3)], dtype=float)
    assert report.inter_rater_alpha == pytest.approx(krippendorff.alpha(
        reliability_data=matrix, level_of_measurement="ordinal", value_domain=[1, 2, 3, 4, 5]))
    auto = [i["automatic_rating"] for i in items]
    human = [per_picture[i["id"]] for i in items]
    if len(set(auto)) > 1:
        assert report.automatic.spearman == pytest.approx(stats.spearmanr(human, auto).statistic)
    assert report.automatic.n == 16
    # Paired: LLM-GROP against TPRA on the same (task, trial), by scipy directly.
    pair = next(p for p in report.paired if (p.first, p.second) == ("tpra", "llm-grop"))
    key = {(i["task"], i["trial"], i["method"]): per_picture[i["id"]] for i in items}
    shared = sorted({(t, k) for t, k, _ in key})
    a = [key[(t, k, "tpra")] for t, k in shared]
    b = [key[(t, k, "llm-grop")] for t, k in shared]
    expected = stats.wilcoxon(np.subtract(a, b))
    assert pair.n == 4 and pair.mean_difference == pytest.approx(mean(a) - mean(b))
    assert pair.p_value == pytest.approx(expected.pvalue)
    assert pair.effect_size == -1.0  # TPRA is rated lower on every trial


def test_paired_comparison_agrees_with_scipy_on_a_hand_made_case() -> None:
    a = [4.0, 3.5, 5.0, 2.0, 4.5, 3.0, 4.0]
    b = [3.0, 3.5, 3.0, 2.5, 2.0, 1.0, 3.5]
    got = compare("x", "y", a, b)
    want = stats.wilcoxon(a, b)
    assert got.n == 7 and got.statistic == want.statistic and got.p_value == want.pvalue
    # Non-zero differences 1, 2, -0.5, 2.5, 2, 0.5 rank 3, 4.5, 1.5, 6, 4.5, 1.5:
    # W+ = 19.5, W- = 1.5, r = 18 / 21.
    assert got.effect_size == pytest.approx(18 / 21)
    same = compare("x", "y", [3, 3], [3, 3])
    assert same.n == 2 and math.isnan(same.p_value) and same.mean_difference == 0


def test_report_files(study, tmp_path: Path) -> None:
    db, _ = study
    rate_all(db, rule)
    conn = connect(db)
    try:
        report = human_report(conn)
    finally:
        conn.close()
    out = tmp_path / "report"
    written = write_report(report, out)
    assert [p.name for p in written] == list(FILES)
    data = json.loads((out / "report.json").read_text())
    assert data["ratings"] == 48 and data["raters"] == 3
    assert {m["method"] for m in data["summary"]["methods"]} == {"tpra", "latp", "grop",
                                                                 "llm-grop"}
    assert len(data["paired"]) == 6
    html = (out / "report.html").read_text()
    assert "Krippendorff" in html and 'src="fig3_rating_vs_time.png"' in html
    assert "<script" not in html
    for fig in ("fig3_rating_vs_time.png", "fig5_rating_per_task.png"):
        assert (out / fig).read_bytes()[:4] == b"\x89PNG"


def test_one_rater_has_no_agreement_figure(study) -> None:
    db, _ = study
    conn = connect(db)
    try:
        store = RatingStore(conn)
        for (item,) in conn.execute("SELECT id FROM items").fetchall():
            store.rate(1, item, 3)
        report = human_report(conn)
    finally:
        conn.close()
    assert report.raters == 1 and math.isnan(report.inter_rater_alpha)
    assert all(math.isnan(p.p_value) for p in report.paired)
    with sqlite3.connect(db) as c:
        assert c.execute("SELECT count(*) FROM ratings").fetchone()[0] == 16
