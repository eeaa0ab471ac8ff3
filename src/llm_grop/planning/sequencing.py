"""The task level: the order in which objects are fetched and placed.

The order minimises a path cost ``first[o1] + edge[o1, o2] + ... + end[on]`` (asymmetric,
seconds) subject to precedence: a support is placed before what rests on it. Up to
``exact_limit`` objects this is solved exactly by dynamic programming over subsets
(Held-Karp, ``O(2^n n^2)``); beyond that, by depth-first branch and bound from a
local-search upper bound, within a node budget (``optimal`` says whether it finished).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from llm_grop.errors import Infeasible


@dataclass(frozen=True)
class Ordering:
    """An order of objects (indices), its cost, whether it is proven optimal, and how many
    search nodes were expanded."""

    order: tuple[int, ...]
    cost: float
    optimal: bool
    expanded: int


def supports_before(names: Sequence[str],
                    on_map: Mapping[str, str | None]) -> list[tuple[int, int]]:
    """Precedence pairs ``(i, j)``: object ``i`` supports object ``j``, so goes first."""
    index = {n: i for i, n in enumerate(names)}
    return [(index[s], index[n]) for n in names
            if (s := on_map.get(n)) is not None and s in index and s != n]


def _cost(order: Sequence[int], first: np.ndarray, edge: np.ndarray, end: np.ndarray) -> float:
    if not order:
        return 0.0
    c = first[order[0]] + end[order[-1]]
    for a, b in zip(order, order[1:], strict=False):
        c += edge[a, b]
    return float(c)


def _check_acyclic(n: int, preds: list[int], names: Sequence[str]) -> None:
    done = 0
    while True:
        ready = [j for j in range(n) if not done >> j & 1 and preds[j] & ~done == 0]
        if not ready:
            break
        for j in ready:
            done |= 1 << j
    if done != (1 << n) - 1:
        stuck = [names[j] for j in range(n) if not done >> j & 1]
        raise Infeasible(f"the objects' supports form a cycle: {', '.join(stuck)}")


def best_order(first: ArrayLike, edge: ArrayLike, end: ArrayLike,
               before: Sequence[tuple[int, int]] = (), *, names: Sequence[str] | None = None,
               exact_limit: int = 12, node_budget: int = 50_000) -> Ordering:
    """The order of least cost with every ``(a, b)`` of ``before`` keeping ``a`` before ``b``.

    ``first[j]``: cost of starting with ``j``; ``edge[i, j]``: of ``j`` right after ``i``;
    ``end[j]``: of finishing with ``j``. Infinite costs forbid. Raises :class:`Infeasible`
    when the precedence is cyclic.
    """
    f = np.asarray(first, dtype=float)
    e = np.asarray(edge, dtype=float)
    z = np.asarray(end, dtype=float)
    n = len(f)
    names = list(names) if names is not None else [str(i) for i in range(n)]
    preds = [0] * n
    for a, b in before:
        preds[b] |= 1 << a
    _check_acyclic(n, preds, names)
    if n == 0:
        return Ordering((), 0.0, True, 0)
    if n <= exact_limit:
        return _held_karp(f, e, z, preds)
    return _branch_and_bound(f, e, z, preds, node_budget)


def _held_karp(f: np.ndarray, e: np.ndarray, z: np.ndarray, preds: list[int]) -> Ordering:
    n = len(f)
    full = 1 << n
    dp = np.full((full, n), np.inf)
    parent = np.full((full, n), -1, dtype=np.int64)
    for j in range(n):
        if preds[j] == 0:
            dp[1 << j, j] = f[j]
    pred_arr = np.array(preds)
    bits = 1 << np.arange(n)
    expanded = 0
    for mask in range(1, full):
        row = dp[mask]
        if not np.isfinite(row).any():
            continue
        expanded += 1
        # via[i, k]: reach k next with i last.
        via = row[:, None] + e
        best_last = np.argmin(via, axis=0)
        best = via[best_last, np.arange(n)]
        allowed = ((mask & bits) == 0) & ((pred_arr & ~mask) == 0) & np.isfinite(best)
        for k in np.flatnonzero(allowed):
            nxt = mask | int(bits[k])
            if best[k] < dp[nxt, k]:
                dp[nxt, k] = best[k]
                parent[nxt, k] = best_last[k]
    total = dp[full - 1] + z
    last = int(np.argmin(total))
    if not np.isfinite(total[last]):
        return Ordering(tuple(range(n)), float("inf"), True, expanded)
    order, mask = [last], full - 1
    while len(order) < n:
        prev = int(parent[mask, order[-1]])
        mask &= ~(1 << order[-1])
        order.append(prev)
    order.reverse()
    return Ordering(tuple(order), float(total[last]), True, expanded)


def _feasible(order: Sequence[int], preds: list[int]) -> bool:
    seen = 0
    for j in order:
        if preds[j] & ~seen:
            return False
        seen |= 1 << j
    return True


def _greedy(f: np.ndarray, e: np.ndarray, z: np.ndarray, preds: list[int]) -> list[int]:
    """Nearest feasible next object each time, then moves of one object elsewhere while
    they lower the cost."""
    n = len(f)
    order: list[int] = []
    seen = 0
    while len(order) < n:
        ready = [j for j in range(n) if not seen >> j & 1 and preds[j] & ~seen == 0]
        step = f if not order else e[order[-1]]
        j = min(ready, key=lambda k: (step[k], k))
        order.append(j)
        seen |= 1 << j
    best = _cost(order, f, e, z)
    improved = True
    while improved:
        improved = False
        for i in range(n):
            for k in range(n):
                if i == k:
                    continue
                trial = order[:i] + order[i + 1:]
                trial.insert(k, order[i])
                if _feasible(trial, preds):
                    c = _cost(trial, f, e, z)
                    if c < best - 1e-12:
                        order, best, improved = trial, c, True
    return order


def _branch_and_bound(f: np.ndarray, e: np.ndarray, z: np.ndarray, preds: list[int],
                      budget: int) -> Ordering:
    n = len(f)
    incumbent = _greedy(f, e, z, preds)
    best = _cost(incumbent, f, e, z)
    finite_e = np.where(np.isfinite(e), e, np.inf)
    # A lower bound on what the objects still to place cost: each needs an arrival.
    min_in = np.minimum(finite_e.min(axis=0), f)
    min_end = float(np.min(z))
    expanded = 0
    exhausted = False
    stack: list[tuple[list[int], int, float]] = [([], 0, 0.0)]
    while stack:
        order, seen, cost = stack.pop()
        expanded += 1
        if expanded > budget:
            exhausted = True
            break
        if len(order) == n:
            total = cost + z[order[-1]]
            if total < best - 1e-12:
                best, incumbent = float(total), order
            continue
        rest = [j for j in range(n) if not seen >> j & 1]
        bound = cost + float(min_in[rest].sum()) + min_end
        if bound >= best - 1e-12:
            continue
        step = f if not order else e[order[-1]]
        ready = [j for j in rest if preds[j] & ~seen == 0 and np.isfinite(step[j])]
        for j in sorted(ready, key=lambda k: -step[k]):
            stack.append((order + [j], seen | 1 << j, cost + float(step[j])))
    return Ordering(tuple(incumbent), best, not exhausted, expanded)
