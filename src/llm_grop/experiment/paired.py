"""Method against method on the same trials: the Wilcoxon signed-rank test (scipy).

Every trial of a benchmark is paired across methods by its seed, so two methods are
compared on the trials both have: the differences ``first - second`` of one value (a
rating, a time) per trial. The effect size is the matched-pairs rank-biserial
correlation: ``(W+ - W-) / (W+ + W-)`` over the ranks of the non-zero differences, from -1
(``second`` always higher) to +1 (``first`` always higher).
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Mapping, Sequence
from dataclasses import dataclass
from itertools import combinations

import numpy as np
from scipy import stats


@dataclass(frozen=True)
class PairedComparison:
    """``first`` against ``second`` on ``n`` shared trials.

    ``mean_difference`` is the mean of ``first - second`` (in the value's unit);
    ``statistic`` and ``p_value`` are scipy's two-sided Wilcoxon signed-rank test (zero
    differences dropped; NaN when every difference is zero); ``effect_size`` is the
    rank-biserial correlation (NaN likewise).
    """

    first: str
    second: str
    n: int
    mean_difference: float
    statistic: float
    p_value: float
    effect_size: float

    def to_json(self) -> dict[str, object]:
        """As plain JSON values, NaN as ``None``."""
        def num(x: float) -> float | None:
            return None if math.isnan(x) else x
        return {"first": self.first, "second": self.second, "n": self.n,
                "mean_difference": num(self.mean_difference),
                "statistic": num(self.statistic), "p_value": num(self.p_value),
                "effect_size": num(self.effect_size)}


def compare(first: str, second: str, a: Sequence[float], b: Sequence[float]
            ) -> PairedComparison:
    """The paired comparison of values ``a`` (of ``first``) and ``b`` (of ``second``),
    which line up trial by trial."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    n = int(d.size)
    mean = float(d.mean()) if n else math.nan
    nonzero = d[d != 0]
    if nonzero.size == 0:
        return PairedComparison(first, second, n, mean, math.nan, math.nan, math.nan)
    result = stats.wilcoxon(d, zero_method="wilcox", alternative="two-sided")
    ranks = stats.rankdata(np.abs(nonzero))
    plus, minus = float(ranks[nonzero > 0].sum()), float(ranks[nonzero < 0].sum())
    return PairedComparison(first, second, n, mean, float(result.statistic),
                            float(result.pvalue), (plus - minus) / (plus + minus))


def paired_comparisons(values: Mapping[str, Mapping[Hashable, float]],
                       order: Sequence[str]) -> tuple[PairedComparison, ...]:
    """Every pair of methods in ``order`` (each earlier one first) compared on the trials
    both have: ``values[method][trial key] = value``. Pairs with no shared trial are left
    out."""
    out = []
    for first, second in combinations(order, 2):
        shared = sorted(values.get(first, {}).keys() & values.get(second, {}).keys(), key=repr)
        if shared:
            out.append(compare(first, second, [values[first][k] for k in shared],
                               [values[second][k] for k in shared]))
    return tuple(out)
