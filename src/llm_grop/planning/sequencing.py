"""The task level: the order in which objects are fetched and placed.

The order minimises a path cost ``first[o1] + edge[o1, o2] + ... + end[on]`` (asymmetric,
seconds) subject to precedence: a support is placed before what rests on it. Up to
``exact_limit`` objects this is solved exactly by dynamic programming over subsets
(Held-Karp, ``O(2^n n^2)``). Beyond that, by local search (:func:`_local_search`:
nearest feasible next object, then the best of every move of one to three consecutive
objects elsewhere and every reversal of a stretch, all scored at once with numpy, while
one lowers the cost), optionally followed by a depth-first branch and bound within a node
budget. Every such order comes with a lower bound on the optimum (:func:`lower_bound`:
the assignment relaxation), so its gap to the optimum is stated, not guessed
(``optimal`` says whether the search proved it optimal).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import linear_sum_assignment

from llm_grop.errors import Infeasible


@dataclass(frozen=True)
class Ordering:
    """An order of objects (indices), its cost, whether it is proven optimal, and how many
    search nodes were expanded."""

    order: tuple[int, ...]
    cost: float
    optimal: bool
    expanded: int
    #: A lower bound on the least cost (``cost`` itself when proven optimal).
    bound: float = float("nan")

    @property
    def gap(self) -> float:
        """How much more ``cost`` may be than the optimum's, in the cost's units (seconds
        for GROP's orders): ``cost - bound``, 0 when proven optimal."""
        return 0.0 if self.optimal else max(self.cost - self.bound, 0.0)


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
        return Ordering((), 0.0, True, 0, 0.0)
    if n <= exact_limit:
        return _held_karp(f, e, z, preds)
    order = _local_search(f, e, z, preds)
    if node_budget > 0:
        found = _branch_and_bound(f, e, z, preds, node_budget, order)
        if found.optimal:
            return replace(found, bound=found.cost)
        order = list(found.order)
    cost = _cost(order, f, e, z)
    bound = lower_bound(f, e, z)
    return Ordering(tuple(order), cost, cost <= bound + 1e-9, 0, min(bound, cost))


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
        return Ordering(tuple(range(n)), float("inf"), True, expanded, float("inf"))
    seq, mask = [end], full - 1
    while len(seq) < n:
        prev = int(parent[mask, seq[-1]])
        mask &= ~(1 << seq[-1])
        seq.append(prev)
    seq.reverse()
    return Ordering(tuple(seq), float(total[end]), True, expanded, float(total[end]))


def _feasible(order: Sequence[int], preds: list[int]) -> bool:
    seen = 0
    for j in order:
        if preds[j] & ~seen:
            return False
        seen |= 1 << j
    return True


def _nearest(f: np.ndarray, e: np.ndarray, preds: list[int]) -> list[int]:
    """The nearest feasible next object each time (ties: the lowest index)."""
    n = len(f)
    order: list[int] = []
    seen = 0
    while len(order) < n:
        ready = [j for j in range(n) if not seen >> j & 1 and preds[j] & ~seen == 0]
        step = f if not order else e[order[-1]]
        j = min(ready, key=lambda k: (step[k], k))
        order.append(j)
        seen |= 1 << j
    return order


def _closed(f: np.ndarray, e: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The path problem as a tour through a depot (index ``n``): ``C[n, j] = f[j]``,
    ``C[j, n] = z[j]``, ``C[i, j] = e[i, j]``, infinite on the diagonal."""
    n = len(f)
    c = np.full((n + 1, n + 1), np.inf)
    c[:n, :n] = e
    c[n, :n], c[:n, n] = f, z
    np.fill_diagonal(c, np.inf)
    return c


#: Moves of this many consecutive objects are tried by the local search.
SEGMENTS = (1, 2, 3)


def _moves(c: np.ndarray, route: np.ndarray) -> list[tuple[float, list[int]]]:
    """Every improving move of ``route`` (depot, the order, depot) as (change of cost,
    the new order), best first: a stretch of :data:`SEGMENTS` objects moved to another
    gap, or a stretch reversed. Precedence is not checked here."""
    m = len(route) - 2
    legs = c[route[:-1], route[1:]]                     # legs[k]: route[k] -> route[k+1]
    found: list[tuple[float, int, int, int]] = []       # (delta, kind, i, g)
    gaps = np.arange(m + 1)
    for length in SEGMENTS:
        if length > m:
            break
        i = np.arange(1, m - length + 2)                 # the segment is route[i:i+length]
        head, tail = route[i], route[i + length - 1]
        a, b = route[i - 1], route[i + length]
        removed = c[a, b] - legs[i - 1] - legs[i + length - 1]
        # Inserting between route[g] and route[g+1], for every gap g outside the segment.
        added = (c[route[gaps][None, :], head[:, None]] + c[tail[:, None], route[gaps + 1][None, :]]
                 - legs[None, :])
        delta = removed[:, None] + added
        inside = (gaps[None, :] >= i[:, None] - 1) & (gaps[None, :] <= (i + length - 1)[:, None])
        delta[inside] = np.inf
        for si, g in zip(*np.nonzero(delta < -1e-9), strict=True):
            found.append((float(delta[si, g]), length, int(i[si]), int(g)))
    if m >= 2:
        # Reversing route[i..j]: legs inside run backwards.
        back = c[route[1:], route[:-1]]                  # back[k]: route[k+1] -> route[k]
        fwd_sum = np.concatenate([[0.0], np.cumsum(np.where(np.isfinite(legs), legs, 1e18))])
        back_sum = np.concatenate([[0.0], np.cumsum(np.where(np.isfinite(back), back, 1e18))])
        ii, jj = np.triu_indices(m + 1, k=1)
        ok = (ii >= 1) & (jj <= m)
        ii, jj = ii[ok], jj[ok]
        inner_old = fwd_sum[jj] - fwd_sum[ii]
        inner_new = back_sum[jj] - back_sum[ii]
        delta = (c[route[ii - 1], route[jj]] + c[route[ii], route[jj + 1]] + inner_new
                 - legs[ii - 1] - legs[jj] - inner_old)
        for k in np.flatnonzero(delta < -1e-9):
            found.append((float(delta[k]), 0, int(ii[k]), int(jj[k])))
    found.sort()
    out = []
    order = route[1:-1].tolist()
    for delta, kind, i, g in found:
        if kind == 0:
            new = order[:i - 1] + order[i - 1:g][::-1] + order[g:]
        else:
            seg = order[i - 1:i - 1 + kind]
            rest = order[:i - 1] + order[i - 1 + kind:]
            at = g if g < i else g - kind
            new = rest[:at] + seg + rest[at:]
        out.append((delta, new))
    return out


def _local_search(f: np.ndarray, e: np.ndarray, z: np.ndarray, preds: list[int],
                  max_rounds: int = 10_000) -> list[int]:
    """A good order: :func:`_nearest`, then the best feasible improving move of
    :func:`_moves` each round while one lowers the cost."""
    return _improve(_nearest(f, e, preds), f, e, z, preds, _closed(f, e, z), max_rounds)


def _improve(order: list[int], f: np.ndarray, e: np.ndarray, z: np.ndarray,
             preds: list[int], c: np.ndarray, max_rounds: int = 10_000) -> list[int]:
    """``order`` after the best feasible improving move of :func:`_moves` each round
    while one lowers the cost."""
    n = len(f)
    best = _cost(order, f, e, z)
    for _ in range(max_rounds):
        route = np.array([n, *order, n])
        for _, new in _moves(c, route):
            if _feasible(new, preds):
                cost = _cost(new, f, e, z)
                # Sums of many legs are compared anew, so rounding never loops.
                if cost < best - 1e-9:
                    order, best = new, cost
                    break
        else:
            break
    return order


#: Objects re-ordered exactly at a time by :func:`refine`.
WINDOW = 8


def refine(first: ArrayLike, edge: ArrayLike, end: ArrayLike, ordering: Ordering,
           before: Sequence[tuple[int, int]] = (), window: int = WINDOW) -> Ordering:
    """``ordering`` improved by exact re-ordering of every ``window`` consecutive objects
    (Held-Karp with the objects before and after held fixed), alternating with the local
    search's moves, until neither lowers the cost; its bound is kept."""
    f, e, z = (np.asarray(a, dtype=float) for a in (first, edge, end))
    n = len(f)
    if ordering.optimal or n <= 2:
        return ordering
    preds = [0] * n
    for a, b in before:
        preds[b] |= 1 << a
    c = _closed(f, e, z)
    order = list(ordering.order)
    best = _cost(order, f, e, z)
    w = min(window, n)
    improved = True
    while improved:
        improved = False
        for s in range(n - w + 1):
            nodes = order[s:s + w]
            head = n if s == 0 else order[s - 1]
            tail = n if s + w == n else order[s + w]
            local = {j: k for k, j in enumerate(nodes)}
            sub_preds = [sum(1 << local[a] for a in range(n) if preds[j] >> a & 1 and a in local)
                         for j in nodes]
            idx = np.array(nodes)
            sub = _held_karp(c[head, idx], c[np.ix_(idx, idx)], c[idx, tail], sub_preds)
            new = order[:s] + [nodes[k] for k in sub.order] + order[s + w:]
            cost = _cost(new, f, e, z)
            if cost < best - 1e-9:
                order, best, improved = new, cost, True
        moved = _improve(order, f, e, z, preds, c)
        cost = _cost(moved, f, e, z)
        if cost < best - 1e-9:
            order, best, improved = moved, cost, True
    return Ordering(tuple(order), best, best <= ordering.bound + 1e-9, ordering.expanded,
                    min(ordering.bound, best))


def lower_bound(first: ArrayLike, edge: ArrayLike, end: ArrayLike) -> float:
    """A lower bound on the least cost of any order (precedence ignored): the assignment
    relaxation of the tour through a depot, in which every object has one predecessor and
    one successor but the legs need not form a single path."""
    c = _closed(np.asarray(first, dtype=float), np.asarray(edge, dtype=float),
                np.asarray(end, dtype=float))
    finite = np.isfinite(c)
    if not finite.any():
        return float("inf")
    # A forbidden leg costs more than any order that uses none: a bound still.
    big = (np.abs(c[finite]).sum() + 1.0) * 2.0
    rows, cols = linear_sum_assignment(np.where(finite, c, big))
    return float(c[rows, cols].sum()) if finite[rows, cols].all() else float("inf")


def _branch_and_bound(f: np.ndarray, e: np.ndarray, z: np.ndarray, preds: list[int],
                      budget: int, incumbent: list[int]) -> Ordering:
    n = len(f)
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
