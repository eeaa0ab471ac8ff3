"""Method against method on the same trials: the Wilcoxon signed-rank test (scipy).

Every trial of a benchmark is paired across methods by its seed, so two methods are
compared on the trials both have: the differences ``first - second`` of one value (a
rating, a time) per trial. The effect size is the matched-pairs rank-biserial
correlation: ``(W+ - W-) / (W+ + W-)`` over the ranks of the non-zero differences, from -1
(``second`` always higher) to +1 (``first`` always higher). The mean difference has a 95 %
bootstrap confidence interval (scipy's BCa over the differences, :data:`RESAMPLES`
resamples, seed stage ``bootstrap``: the same values always give the same interval).
"""

from __future__ import annotations

import math
import warnings
from collections import defaultdict
from collections.abc import Hashable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from itertools import combinations
from typing import Protocol

import numpy as np
from scipy import stats

from llm_grop import seeds

#: Bootstrap resamples behind a mean difference's confidence interval.
RESAMPLES = 9999
#: The confidence interval's level.
CONFIDENCE = 0.95


@dataclass(frozen=True)
class PairedComparison:
    """``first`` against ``second`` on ``n`` shared trials.

    ``mean_difference`` is the mean of ``first - second`` (in the value's unit), and
    ``ci_low``/``ci_high`` its 95 % bootstrap confidence interval (NaN with fewer than two
    trials; the mean itself when every difference is the same); ``statistic`` and
    ``p_value`` are scipy's two-sided Wilcoxon signed-rank test (zero differences dropped;
    NaN when every difference is zero); ``effect_size`` is the rank-biserial correlation
    (NaN likewise).
    """

    first: str
    second: str
    n: int
    mean_difference: float
    statistic: float
    p_value: float
    effect_size: float
    ci_low: float = math.nan
    ci_high: float = math.nan

    def to_json(self) -> dict[str, object]:
        """As plain JSON values, NaN as ``None``."""
        def num(x: float) -> float | None:
            return None if math.isnan(x) else x
        return {"first": self.first, "second": self.second, "n": self.n,
                "mean_difference": num(self.mean_difference),
                "ci95": [num(self.ci_low), num(self.ci_high)],
                "statistic": num(self.statistic), "p_value": num(self.p_value),
                "effect_size": num(self.effect_size)}


def compare(first: str, second: str, a: Sequence[float], b: Sequence[float],
            rng: np.random.Generator | None = None) -> PairedComparison:
    """The paired comparison of values ``a`` (of ``first``) and ``b`` (of ``second``),
    which line up trial by trial; ``rng`` draws the bootstrap's resamples (default: seed 0's
    ``bootstrap`` stream)."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    n = int(d.size)
    mean = float(d.mean()) if n else math.nan
    low, high = _interval(d, rng if rng is not None else seeds.stream(0, "bootstrap"))
    nonzero = d[d != 0]
    if nonzero.size == 0:
        return PairedComparison(first, second, n, mean, math.nan, math.nan, math.nan,
                                low, high)
    result = stats.wilcoxon(d, zero_method="wilcox", alternative="two-sided")
    ranks = stats.rankdata(np.abs(nonzero))
    plus, minus = float(ranks[nonzero > 0].sum()), float(ranks[nonzero < 0].sum())
    return PairedComparison(first, second, n, mean, float(result.statistic),
                            float(result.pvalue), (plus - minus) / (plus + minus), low, high)


def _interval(d: np.ndarray, rng: np.random.Generator) -> tuple[float, float]:
    """The bootstrap confidence interval of the mean of ``d``."""
    if d.size < 2:
        return math.nan, math.nan
    if np.all(d == d[0]):
        return float(d[0]), float(d[0])  # every resample has this mean
    # BCa warns, and answers NaN, when nearly every resample has one mean; the percentile
    # interval then stands in.
    for method in ("BCa", "percentile"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ci = stats.bootstrap((d,), np.mean, n_resamples=RESAMPLES,
                                 confidence_level=CONFIDENCE, method=method,
                                 random_state=rng).confidence_interval
        if not (math.isnan(ci.low) or math.isnan(ci.high)):
            break
    return float(ci.low), float(ci.high)


def paired_comparisons(values: Mapping[str, Mapping[Hashable, float]],
                       order: Sequence[str], seed: int = 0) -> tuple[PairedComparison, ...]:
    """Every pair of methods in ``order`` (each earlier one first) compared on the trials
    both have: ``values[method][trial key] = value``. Pairs with no shared trial are left
    out. The k-th pair's bootstrap draws from ``seed``'s ``bootstrap`` stream at path k."""
    out = []
    for k, (first, second) in enumerate(combinations(order, 2)):
        shared = sorted(values.get(first, {}).keys() & values.get(second, {}).keys(), key=repr)
        if shared:
            out.append(compare(first, second, [values[first][key] for key in shared],
                               [values[second][key] for key in shared],
                               seeds.stream(seed, "bootstrap", k)))
    return tuple(out)


#: What a bench compares its methods on, trial by trial: the rating (1-5) and the execution
#: time (seconds; trials without a plan have none and are left out of their pairs).
PAIRED_VALUES = ("rating", "execution_time_s")


class Trial(Protocol):
    """What a paired comparison needs of one trial (a bench's trial row has it)."""

    @property
    def method(self) -> str: ...
    @property
    def task(self) -> int: ...
    @property
    def trial(self) -> int: ...
    @property
    def rating(self) -> float: ...
    @property
    def execution_time_s(self) -> float | None: ...


def paired_by_trial(rows: Iterable[Trial], order: Sequence[str], seed: int = 0
                    ) -> dict[str, tuple[PairedComparison, ...]]:
    """Every pair of methods in ``order`` compared on each of :data:`PAIRED_VALUES`, over
    the ``(task, trial)`` pairs both have a value for; the bootstrap draws from ``seed``
    (the bench's)."""
    rows = list(rows)
    out = {}
    for value in PAIRED_VALUES:
        values: dict[str, dict[Hashable, float]] = defaultdict(dict)
        for r in rows:
            v = getattr(r, value)
            if v is not None:
                values[r.method][(r.task, r.trial)] = float(v)
        out[value] = paired_comparisons(values, order, seed)
    return out
