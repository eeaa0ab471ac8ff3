"""clingo consistency (paper §III-A): the paper's conflict, minimal cores, largest subsets.

Besides hand-written cases, the ASP encoding is compared with a brute-force oracle
written independently in Python (every placement of up to four objects on a small
grid, plus the stacking and centre conventions), and with relations read off
random grid positions, which must always be consistent.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from llm_grop.arrangement.consistency import (
    ConsistencyReport,
    check,
    largest_consistent_subset,
    minimal_conflict,
)
from llm_grop.arrangement.predicates import rests_on_edges, stacked_pairs
from llm_grop.world.relation import CONVERSE, DIRECTION, RELATION_NAMES, Relation

R = Relation

PAPER = [
    R("fruit bowl", "center", None, "1"),
    R("butter knife", "above and to the right of", "fruit bowl", "2"),
    R("dinner fork", "to the left of", "butter knife", "3"),
    R("dinner knife", "to the right of", "butter knife", "4"),
    R("fruit bowl", "to the right of", "dinner fork", "5"),
    R("water cup", "below and to the left of", "dinner knife", "6"),
]


def _lines(rels: Sequence[Relation]) -> list[str]:
    return [r.line for r in rels]


def _numbered(*triples: tuple[str, str, str | None]) -> list[Relation]:
    """Relations whose ``line`` is their 1-based position, to compare conflicts by line."""
    return [R(s, rel, o, str(i)) for i, (s, rel, o) in enumerate(triples, 1)]


def test_paper_example_conflict_is_lines_2_3_5() -> None:
    report = check(PAPER)
    assert report == ConsistencyReport(False, (PAPER[1], PAPER[2], PAPER[4]))
    assert minimal_conflict(PAPER) == report.conflict
    # The order of the input does not change which lines conflict.
    assert sorted(_lines(check(PAPER[::-1]).conflict)) == ["2", "3", "5"]


def test_largest_subset_of_paper_example_drops_line_5() -> None:
    kept = largest_consistent_subset(PAPER)
    assert _lines(kept) == ["1", "2", "3", "4", "6"]  # earlier lines win the tie
    assert check(kept).consistent


def test_typical_setting_is_consistent() -> None:
    rels = [R("dinner plate", "center", None), R("dinner fork", "to the left of", "dinner plate"),
            R("dinner knife", "to the right of", "dinner plate"),
            R("cup", "above and to the right of", "dinner plate"),
            R("mug", "on top of", "mug mat"), R("lid", "on top of", "mug")]
    assert check(rels) == ConsistencyReport(True, ())
    assert minimal_conflict(rels) == ()
    assert largest_consistent_subset(rels) == tuple(rels)
    # The centre holds one stack at most, and the mug's stack is not the plate's.
    extra = R("mug", "center", None)
    assert check([*rels, extra]).conflict == (rels[0], extra)


INCONSISTENT = {
    "left and right of each other": [("a", "to the left of", "b"), ("a", "to the right of", "b")],
    "each left of the other": [("a", "to the left of", "b"), ("b", "to the left of", "a")],
    "3-cycle of left of": [("a", "to the left of", "b"), ("b", "to the left of", "c"),
                           ("c", "to the left of", "a")],
    "3-cycle of above via converse": [("a", "above", "b"), ("c", "below", "b"),
                                      ("c", "above", "a")],
    "cardinal and diagonal for one pair": [("a", "above", "b"),
                                           ("a", "above and to the left of", "b")],
    "one row, then a diagonal": [("a", "to the left of", "b"), ("b", "to the left of", "c"),
                                 ("a", "above and to the left of", "c")],
    "one column, then left of": [("a", "above", "b"), ("c", "above", "b"),
                                 ("a", "to the left of", "c")],
    "diagonal step leaves the column": [("a", "to the left of", "b"), ("b", "below", "c"),
                                        ("a", "below", "c")],
    "the paper's rule, through others": [("a", "below", "b"),
                                         ("b", "below and to the left of", "c"),
                                         ("a", "to the right of", "c")],
    "stacking 2-cycle": [("a", "on top of", "b"), ("b", "on top of", "a")],
    "stacking 3-cycle": [("a", "on top of", "b"), ("c", "under", "b"), ("a", "under", "c")],
    "two supports": [("a", "on top of", "b"), ("c", "under", "a")],
    "stacked pair also left of": [("a", "on top of", "b"), ("a", "to the left of", "b")],
    "stack apart through a third": [("a", "on top of", "b"), ("c", "to the left of", "a"),
                                    ("b", "to the left of", "c")],
    "two-level stack also diagonal": [("a", "on top of", "b"), ("b", "on top of", "c"),
                                      ("c", "below and to the right of", "a")],
    "two objects at the centre": [("a", "center", None), ("b", "center", None)],
    "self, left of": [("a", "to the left of", "a")],
    "self, on top of": [("a", "on top of", "a")],
}


@pytest.mark.parametrize("triples", INCONSISTENT.values(), ids=INCONSISTENT.keys())
def test_inconsistent_and_every_line_is_needed(
        triples: list[tuple[str, str, str | None]]) -> None:
    rels = _numbered(*triples)
    report = check(rels)
    assert not report.consistent
    assert report.conflict == tuple(rels)


CONSISTENT = {
    "diagonal and cardinal agree": [("a", "above and to the left of", "b"),
                                    ("c", "to the right of", "b"),
                                    ("a", "above and to the left of", "c")],
    "row then column gives a diagonal": [("a", "to the left of", "b"), ("b", "below", "c"),
                                         ("a", "below and to the left of", "c")],
    "a stack at the centre": [("a", "on top of", "b"), ("b", "center", None),
                              ("a", "center", None)],
    "a two-level stack at the centre": [("a", "on top of", "b"), ("c", "under", "b"),
                                        ("a", "center", None), ("c", "center", None)],
    "a stack beside a plate": [("mat", "to the right of", "plate"), ("mug", "on top of", "mat"),
                               ("mug", "to the right of", "plate")],
    "two things on one support": [("a", "on top of", "c"), ("b", "on top of", "c")],
    "repeats and converses": [("a", "to the left of", "b"), ("b", "to the right of", "a"),
                              ("a", "to the left of", "b"), ("a", "under", "c"),
                              ("c", "on top of", "a"), ("d", "center", None),
                              ("d", "center", None)],
}


@pytest.mark.parametrize("triples", CONSISTENT.values(), ids=CONSISTENT.keys())
def test_consistent(triples: list[tuple[str, str, str | None]]) -> None:
    rels = _numbered(*triples)
    assert check(rels) == ConsistencyReport(True, ())


def test_center_conflict_is_one_unstacked_pair() -> None:
    rels = _numbered(("a", "center", None), ("b", "center", None), ("c", "center", None),
                     ("a", "on top of", "b"))
    conflict = check(rels).conflict
    assert len(conflict) == 2 and rels[2] in conflict
    assert all(r.relation == "center" for r in conflict)


def test_ties_go_to_earlier_lines() -> None:
    left, right = R("a", "to the left of", "b"), R("a", "to the right of", "b")
    assert largest_consistent_subset([left, right]) == (left,)
    assert largest_consistent_subset([right, left]) == (right,)
    cycle = _numbered(("a", "to the left of", "b"), ("b", "to the left of", "c"),
                      ("c", "to the left of", "a"), ("d", "above", "a"))
    assert _lines(largest_consistent_subset(cycle)) == ["1", "2", "4"]


def test_odd_names_are_data_not_code() -> None:
    names = ['chef\'s "special" plate', "tasse à café", "x). :- a. %", "1", "keep(0)", ""]
    rels = [R(a, "to the left of", b) for a, b in itertools.pairwise(names)]
    assert check(rels).consistent
    assert check([*rels, R(names[0], "center", None)]).consistent
    bad = [*rels, R(names[-1], "to the left of", names[0])]
    assert check(bad).conflict == tuple(bad)
    # Only equal strings are the same object.
    assert check([R("Mug", "to the left of", "a"), R("mug", "to the right of", "a")]).consistent


def test_empty_input() -> None:
    assert check([]) == ConsistencyReport(True, ())
    assert minimal_conflict([]) == ()
    assert largest_consistent_subset([]) == ()


def test_clingo_prints_nothing(capfd: pytest.CaptureFixture[str]) -> None:
    check(PAPER)
    largest_consistent_subset(PAPER)
    check(list(PAPER[:4]))
    assert capfd.readouterr() == ("", "")


# --- Brute-force oracle ----------------------------------------------------------------


def _realisable(rels: Sequence[Relation]) -> bool:
    """Whether some grid placement satisfies ``rels`` (and the conventions), by search."""
    said: dict[tuple[str, str], str] = {}
    for r in rels:
        if r.reference is None:
            continue
        if r.subject == r.reference:
            return False
        s, rel, o = r.subject, r.relation, r.reference
        if s > o:
            s, rel, o = o, CONVERSE[rel], s
        if said.setdefault((s, o), rel) != rel:
            return False
    edges = rests_on_edges(r.key() for r in rels)
    support: dict[str, str] = {}
    for upper, lower in edges:
        if support.setdefault(upper, lower) != lower:
            return False
    for start in support:
        node, steps = start, 0
        while node in support and steps <= len(support):
            node, steps = support[node], steps + 1
            if node == start:
                return False
    stacked = stacked_pairs(edges)
    centre = sorted({r.subject for r in rels if r.reference is None})
    if any(frozenset(p) not in stacked for p in itertools.combinations(centre, 2)):
        return False
    names = sorted({n for s, o in said for n in (s, o)})
    if not names:
        return True
    k = len(names)
    # k values per axis realise every weak order of k objects, so this grid suffices.
    grid = np.array(list(itertools.product(range(k), repeat=k)))
    col = {n: i for i, n in enumerate(names)}
    for axis in (0, 1):
        ok = np.ones(len(grid), dtype=bool)
        for (s, o), rel in said.items():
            ok &= np.sign(grid[:, col[s]] - grid[:, col[o]]) == DIRECTION[rel][axis]
        if not ok.any():
            return False
    return True


_OBJECTS = st.sampled_from(["o0", "o1", "o2", "o3"])


@st.composite
def _relations(draw: st.DrawFn) -> Relation:
    rel = draw(st.sampled_from(RELATION_NAMES))
    return R(draw(_OBJECTS), rel, None if rel == "center" else draw(_OBJECTS))


@settings(max_examples=150, deadline=None, derandomize=True)
@given(st.lists(_relations(), min_size=1, max_size=7))
def test_agrees_with_brute_force(rels: list[Relation]) -> None:
    rels = [R(r.subject, r.relation, r.reference, str(i)) for i, r in enumerate(rels)]
    report = check(rels)
    assert report.consistent == _realisable(rels)
    if not report.consistent:
        conflict = list(report.conflict)
        assert conflict == [r for r in rels if r in conflict], "conflict is in input order"
        assert not _realisable(conflict)
        for size in range(len(conflict)):
            assert all(_realisable(sub) for sub in itertools.combinations(conflict, size)), \
                "every proper subset of the conflict must be consistent"
    kept = largest_consistent_subset(rels)
    # The expected answer: most lines, then lexicographically earliest lines kept.
    best = max((mask for mask in itertools.product((1, 0), repeat=len(rels))
                if _realisable([r for r, m in zip(rels, mask, strict=True) if m])),
               key=lambda mask: (sum(mask), mask))
    assert kept == tuple(r for r, m in zip(rels, best, strict=True) if m)
    assert check(kept).consistent


# --- Relations read off real positions ---------------------------------------------------

_NAME_OF = {d: rel for rel, d in DIRECTION.items() if d != (0, 0)}


def _sign(v: int) -> int:
    return (v > 0) - (v < 0)


@settings(max_examples=80, deadline=None, derandomize=True)
@given(st.lists(st.tuples(st.integers(0, 3), st.integers(0, 3)), min_size=1, max_size=8),
       st.randoms(use_true_random=False))
def test_relations_read_off_grid_positions_are_consistent(points, rnd) -> None:
    names = [f"object {i}" for i in range(len(points))]
    rels: list[Relation] = []
    # Objects on one grid point form a stack, in index order, with every step stated.
    stacks: dict[tuple[int, int], list[int]] = {}
    for i, p in enumerate(points):
        stacks.setdefault(p, []).append(i)
    for members in stacks.values():
        for lower, upper in itertools.pairwise(members):
            rels.append(R(names[upper], "on top of", names[lower]))
    for (i, p), (j, q) in itertools.combinations(enumerate(points), 2):
        if p != q and rnd.random() < 0.6:
            rels.append(R(names[i], _NAME_OF[(_sign(p[0] - q[0]), _sign(p[1] - q[1]))],
                          names[j]))
    centre = rnd.choice(list(stacks.values()))
    rels += [R(names[i], "center", None) for i in centre if rnd.random() < 0.7]
    # Restate some relations, some from the other side; shuffle the lines.
    rels += [r.converse() if r.reference is not None and rnd.random() < 0.5 else r
             for r in rels if rnd.random() < 0.3]
    rnd.shuffle(rels)
    assert check(rels) == ConsistencyReport(True, ())
    assert largest_consistent_subset(rels) == tuple(rels)


# --- Every relation of the table, pairwise ------------------------------------------------


@pytest.mark.parametrize("first", [r for r in RELATION_NAMES if r != "center"])
def test_one_relation_per_pair_and_converses_agree(first: str) -> None:
    """For one pair, a relation holds with itself and its converse said from the other side,
    and with no other relation: the table gives no two relations one meaning."""
    a_b = R("a", first, "b")
    assert check([a_b, a_b.converse()]).consistent
    for second in RELATION_NAMES:
        if second == "center":
            continue
        assert check([a_b, R("a", second, "b")]).consistent == (second == first), second


def test_asp_name_is_still_importable_from_here() -> None:
    from llm_grop.arrangement.consistency import ASP_NAME
    assert ASP_NAME["to the left of"] == "left"
    assert set(ASP_NAME) == set(RELATION_NAMES)
