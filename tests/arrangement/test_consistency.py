"""clingo consistency: the paper's conflict, minimal cores, largest consistent subsets."""

from __future__ import annotations

import itertools

from hypothesis import given, settings
from hypothesis import strategies as st

from llm_grop.arrangement.consistency import check, largest_consistent_subset
from llm_grop.world.relation import Relation

R = Relation

PAPER = [
    R("fruit bowl", "center", None, "1"),
    R("butter knife", "above and to the right of", "fruit bowl", "2"),
    R("dinner fork", "to the left of", "butter knife", "3"),
    R("dinner knife", "to the right of", "butter knife", "4"),
    R("fruit bowl", "to the right of", "dinner fork", "5"),
    R("water cup", "below and to the left of", "dinner knife", "6"),
]


def test_paper_example_conflict_is_lines_2_3_5() -> None:
    report = check(PAPER)
    assert not report.consistent
    assert [r.line for r in report.conflict] == ["2", "3", "5"]


def test_largest_subset_of_paper_example_drops_one_line() -> None:
    kept = largest_consistent_subset(PAPER)
    assert len(kept) == 5 and check(kept).consistent
    assert [r.line for r in kept] == ["1", "2", "3", "4", "6"]  # earlier lines win ties


def test_typical_setting_is_consistent() -> None:
    rels = [R("dinner plate", "center", None), R("dinner fork", "to the left of", "dinner plate"),
            R("dinner knife", "to the right of", "dinner plate"),
            R("water cup", "above and to the right of", "dinner plate"),
            R("mug mat", "to the right of", "dinner knife"), R("mug", "on top of", "mug mat"),
            R("mug lid", "on top of", "mug"), R("mug", "center", None)]
    assert check(rels[:-1]).consistent
    # The centre holds one stack at most: the mug is not on the plate.
    assert not check(rels).consistent


def _inconsistent(*rels: Relation) -> bool:
    return not check(list(rels)).consistent


def test_contradictions() -> None:
    assert _inconsistent(R("a", "to the left of", "b"), R("a", "to the right of", "b"))
    assert _inconsistent(R("a", "to the left of", "b"), R("b", "to the left of", "c"),
                         R("c", "to the left of", "a"))
    assert _inconsistent(R("a", "to the left of", "b"), R("a", "above", "b"))
    assert _inconsistent(R("a", "below", "b"), R("b", "below and to the left of", "c"),
                         R("a", "to the right of", "c"))
    assert _inconsistent(R("a", "to the left of", "a"))
    assert _inconsistent(R("a", "center", None), R("b", "center", None))


def test_stacking_rules() -> None:
    assert _inconsistent(R("a", "on top of", "b"), R("b", "on top of", "a"))
    assert _inconsistent(R("a", "on top of", "b"), R("b", "under", "c"), R("c", "on top of", "a"))
    assert _inconsistent(R("a", "on top of", "b"), R("a", "on top of", "c"))
    assert _inconsistent(R("a", "on top of", "b"), R("c", "to the left of", "b"),
                         R("a", "to the right of", "c"), R("a", "above", "c"))
    # A stack may sit at the centre as a whole.
    assert check([R("a", "on top of", "b"), R("b", "center", None), R("a", "center", None)]
                 ).consistent


def test_converse_duplicates_and_odd_names_are_fine() -> None:
    odd = 'chef\'s "special" plate. :- x'
    rels = [R(odd, "to the left of", "mug"), R("mug", "to the right of", odd),
            R("mug", "to the right of", odd), R("tasse à café", "under", "mug")]
    assert check(rels).consistent
    assert check([]).consistent and largest_consistent_subset([]) == ()


_DIRS = {(-1, 0): "to the left of", (1, 0): "to the right of", (0, 1): "above",
         (0, -1): "below", (-1, 1): "above and to the left of", (1, 1): "above and to the right of",
         (-1, -1): "below and to the left of", (1, -1): "below and to the right of"}


def _sign(v: int) -> int:
    return (v > 0) - (v < 0)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.lists(st.tuples(st.integers(0, 3), st.integers(0, 3)), min_size=2, max_size=6,
                unique=True), st.randoms(use_true_random=False))
def test_relations_read_off_real_positions_are_consistent(points, rnd) -> None:
    names = [f"o{i}" for i in range(len(points))]
    rels = []
    for (i, p), (j, q) in itertools.combinations(enumerate(points), 2):
        if rnd.random() < 0.6:
            rels.append(R(names[i], _DIRS[(_sign(p[0] - q[0]), _sign(p[1] - q[1]))], names[j]))
    assert check(rels).consistent


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.lists(st.tuples(st.integers(0, 3), st.sampled_from(sorted(_DIRS.values())),
                          st.integers(0, 3)), min_size=1, max_size=6))
def test_largest_subset_is_consistent_and_maximum(triples) -> None:
    rels = [R(f"o{a}", rel, f"o{b}") for a, rel, b in triples]
    kept = largest_consistent_subset(rels)
    assert check(kept).consistent
    for size in range(len(kept) + 1, len(rels) + 1):
        for combo in itertools.combinations(rels, size):
            assert not check(list(combo)).consistent
    report = check(rels)
    if not report.consistent:
        core = list(report.conflict)
        assert not check(core).consistent
        for k in range(len(core)):
            assert check(core[:k] + core[k + 1:]).consistent, "the conflict must be minimal"
