"""The task level: exact and bounded search for the order of objects."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from llm_grop.errors import Infeasible
from llm_grop.planning.sequencing import best_order, supports_before


def _brute(first, edge, end, before):  # type: ignore[no-untyped-def]
    best = (np.inf, ())
    for perm in itertools.permutations(range(len(first))):
        pos = {j: i for i, j in enumerate(perm)}
        if any(pos[a] > pos[b] for a, b in before):
            continue
        c = first[perm[0]] + end[perm[-1]] + sum(edge[a, b] for a, b in
                                             zip(perm, perm[1:], strict=False))
        best = min(best, (c, perm))
    return best


@pytest.mark.parametrize("seed", range(6))
def test_exact_matches_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 6
    first, end = rng.uniform(0, 10, n), rng.uniform(0, 10, n)
    edge = rng.uniform(0, 10, (n, n))
    before = [(0, 3), (3, 5)] if seed % 2 else []
    got = best_order(first, edge, end, before)
    cost, _ = _brute(first, edge, end, before)
    assert got.optimal and got.cost == pytest.approx(cost)
    pos = {j: i for i, j in enumerate(got.order)}
    assert all(pos[a] < pos[b] for a, b in before)


def test_branch_and_bound_matches_exact() -> None:
    rng = np.random.default_rng(3)
    n = 9
    pts = rng.uniform(0, 5, (n, 2))
    edge = np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))
    first, end = np.hypot(*pts.T), np.zeros(n)
    before = [(1, 2), (4, 7)]
    exact = best_order(first, edge, end, before)
    bnb = best_order(first, edge, end, before, exact_limit=0, node_budget=10**6)
    assert bnb.optimal and bnb.cost == pytest.approx(exact.cost)


def test_twenty_objects_keep_precedence_within_budget() -> None:
    rng = np.random.default_rng(1)
    n = 20
    pts = rng.uniform(0, 5, (n, 2))
    edge = np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1))
    before = [(0, 1), (1, 2), (5, 6)]
    got = best_order(np.hypot(*pts.T), edge, np.zeros(n), before, node_budget=5000)
    assert sorted(got.order) == list(range(n)) and got.expanded <= 5001
    pos = {j: i for i, j in enumerate(got.order)}
    assert pos[0] < pos[1] < pos[2] and pos[5] < pos[6]


def test_supports_before_and_cycles() -> None:
    names = ["mug lid", "mug", "mug mat"]
    pairs = supports_before(names, {"mug lid": "mug", "mug": "mug mat", "mug mat": None})
    assert sorted(pairs) == [(1, 0), (2, 1)]
    with pytest.raises(Infeasible, match="cycle"):
        best_order(np.zeros(2), np.zeros((2, 2)), np.zeros(2), [(0, 1), (1, 0)],
                   names=["a", "b"])
