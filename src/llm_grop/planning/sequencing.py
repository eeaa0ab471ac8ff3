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
               exact_limit: int = 12, node_budget: int = 10_000) -> Ordering:
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
    """Exact dynamic programming over subsets, one layer of equal-sized subsets at a time."""
    n = len(f)
    full = 1 << n
    dp = np.full((full, n), np.inf)
    parent = np.full((full, n), -1, dtype=np.int64)
    pred_arr = np.array(preds, dtype=np.int64)
    bits = np.int64(1) << np.arange(n, dtype=np.int64)
    starts = np.flatnonzero(pred_arr == 0)
    dp[bits[starts], starts] = f[starts]
    all_masks = np.arange(full, dtype=np.int64)
    size = np.zeros(full, dtype=np.int64)
    for b in bits:
        size += (all_masks & b) > 0
    expanded = 0
    for k in range(1, n):
        masks = all_masks[size == k]
        rows = dp[masks]
        live = np.isfinite(rows).any(axis=1)
        masks, rows = masks[live], rows[live]
        expanded += len(masks)
        if not len(masks):
            break
        via = rows[:, :, None] + e[None, :, :]
        last = np.argmin(via, axis=1)
        best = np.take_along_axis(via, last[:, None, :], axis=1)[:, 0, :]
        allowed = ((masks[:, None] & bits[None, :]) == 0) \
            & ((pred_arr[None, :] & ~masks[:, None]) == 0) & np.isfinite(best)
        s_idx, nxt = np.nonzero(allowed)
        target = masks[s_idx] | bits[nxt]
        value = best[s_idx, nxt]
        # With repeated targets the last write wins, so write the smallest value last.
        order = np.argsort(-value, kind="stable")
        dp[target[order], nxt[order]] = value[order]
        parent[target[order], nxt[order]] = last[s_idx, nxt][order]
    total = dp[full - 1] + z
    end = int(np.argmin(total))
    if not np.isfinite(total[end]):
        return Ordering(tuple(range(n)), float("inf"), True, expanded)
    seq, mask = [end], full - 1
    while len(seq) < n:
        prev = int(parent[mask, seq[-1]])
        mask &= ~(1 << seq[-1])
        seq.append(prev)
    seq.reverse()
    return Ordering(tuple(seq), float(total[end]), True, expanded)


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
        rest = np.array([j for j in range(n) if not seen >> j & 1])
        # Every object still to place needs an arrival: from the last one placed or from
        # another object still to place; and the plan still has to end.
        if order:
            into = e[np.append(rest, order[-1])][:, rest]
            np.fill_diagonal(into, np.inf)
            arrivals = into.min(axis=0)
        else:
            into = e[np.ix_(rest, rest)].copy()
            np.fill_diagonal(into, np.inf)
            arrivals = np.minimum(into.min(axis=0), f[rest])
        bound = cost + float(arrivals.sum()) + float(z[rest].min())
        if bound >= best - 1e-12:
            continue
        step = f if not order else e[order[-1]]
        ready = [int(j) for j in rest if preds[j] & ~seen == 0 and np.isfinite(step[j])]
        for j in sorted(ready, key=lambda k: -step[k]):
            stack.append((order + [j], seen | 1 << j, cost + float(step[j])))
    return Ordering(tuple(incumbent), best, not exhausted, expanded)
