"""Paired statistics of a bench: method against method on the same seeds, checked
against scipy on a hand-made case, and written into summary.md and summary.json."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from llm_grop import seeds
from llm_grop.contract.models import TrialRow
from llm_grop.experiment.paired import RESAMPLES, compare, paired_by_trial
from llm_grop.experiment.runner import write_reports
from rows import trial_row

# Seven trials of task 1 (and trial 6 of A has no plan, so no execution time).
A_RATINGS = [4, 3, 5, 2, 4, 3, 4]
B_RATINGS = [3, 3, 3, 2, 2, 1, 3]
A_TIMES = [120.0, 131.5, 118.2, 140.0, 125.5, 133.0, None]
B_TIMES = [126.0, 130.0, 129.9, 151.5, 127.0, 139.5, 141.0]


def _rows() -> list[TrialRow]:
    rows = []
    for k in range(7):
        rows.append(TrialRow.model_validate(trial_row("a", 1, A_RATINGS[k], A_TIMES[k],
                                                      trial=k)))
        rows.append(TrialRow.model_validate(trial_row("b", 1, B_RATINGS[k], B_TIMES[k],
                                                      trial=k)))
    return rows


def test_paired_comparisons_agree_with_scipy_on_a_hand_made_case() -> None:
    paired = paired_by_trial(_rows(), ("a", "b"), seed=3)
    (rating,) = paired["rating"]
    want = stats.wilcoxon(A_RATINGS, B_RATINGS)
    assert (rating.first, rating.second, rating.n) == ("a", "b", 7)
    assert rating.statistic == want.statistic and rating.p_value == want.pvalue
    assert rating.mean_difference == pytest.approx(np.mean(np.subtract(A_RATINGS, B_RATINGS)))
    # Non-zero differences 1, 2, 2, 2, 1 (two ties at 0 dropped) all favour a: r = +1.
    assert rating.effect_size == 1.0
    d = np.subtract(A_RATINGS, B_RATINGS).astype(float)
    ci = stats.bootstrap((d,), np.mean, n_resamples=RESAMPLES, confidence_level=0.95,
                         method="BCa", random_state=seeds.stream(3, "bootstrap", 0))
    assert (rating.ci_low, rating.ci_high) == (ci.confidence_interval.low,
                                               ci.confidence_interval.high)
    assert rating.ci_low < rating.mean_difference < rating.ci_high

    (time,) = paired["execution_time_s"]
    a, b = A_TIMES[:6], B_TIMES[:6]  # trial 6 has no pair
    want = stats.wilcoxon(a, b)
    assert time.n == 6 and time.statistic == want.statistic and time.p_value == want.pvalue
    # Differences -6, 1.5, -11.7, -11.5, -1.5, -6.5 rank 3, 1.5, 6, 5, 1.5, 4 (ties at
    # |1.5| averaged): W+ = 1.5, W- = 19.5, so r = (1.5 - 19.5) / 21.
    assert time.effect_size == pytest.approx((1.5 - 19.5) / 21)


def test_the_bootstrap_repeats_for_a_seed_and_covers_degenerate_cases() -> None:
    first = paired_by_trial(_rows(), ("a", "b"), seed=5)
    assert paired_by_trial(_rows(), ("a", "b"), seed=5) == first
    same = compare("x", "y", [2, 2, 2], [1, 1, 1])
    assert (same.ci_low, same.ci_high) == (1.0, 1.0) and math.isnan(same.p_value) is False
    one = compare("x", "y", [2], [1])
    assert math.isnan(one.ci_low) and one.n == 1


def test_summary_files_hold_the_paired_comparisons(tmp_path: Path) -> None:
    write_reports(tmp_path, _rows(), seed=3)
    data = json.loads((tmp_path / "summary.json").read_text())
    rating = data["paired"]["rating"][0]
    assert rating["first"] == "a" and rating["n"] == 7
    assert rating["p_value"] == stats.wilcoxon(A_RATINGS, B_RATINGS).pvalue
    assert len(rating["ci95"]) == 2 and rating["ci95"][0] < rating["ci95"][1]
    assert data["paired"]["execution_time_s"][0]["n"] == 6
    text = (tmp_path / "summary.md").read_text()
    assert "Paired comparisons on the same task and trial" in text
    assert "| rating | a | b | 7 | 1.14 |" in text and "| time (s) | a | b | 6 |" in text
