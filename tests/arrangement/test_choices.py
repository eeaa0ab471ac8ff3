"""Ambiguous stated relations resolved with clingo (:func:`consistency.choose`).

"The knife beside the plate" is a choice of left or right; "the fork and the knife either
side of the plate" a choice of two pairs. Hand-written cases, then a comparison with a
brute-force resolver built on :func:`consistency.check` over every selection.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st

from llm_grop.arrangement.consistency import Resolution, check, choose
from llm_grop.world.relation import RELATION_NAMES, Choice, Relation

R = Relation
LEFT, RIGHT, ABOVE = "to the left of", "to the right of", "above"


def beside(subject: str, reference: str, words: str = "") -> Choice:
    """"``subject`` beside ``reference``": left of it or right of it."""
    return Choice(((R(subject, LEFT, reference),), (R(subject, RIGHT, reference),)), words)


def either_side(a: str, b: str, reference: str) -> Choice:
    """"``a`` and ``b`` either side of ``reference``": a left and b right, or the reverse."""
    return Choice(((R(a, LEFT, reference), R(b, RIGHT, reference)),
                   (R(a, RIGHT, reference), R(b, LEFT, reference))), "either side of")


def test_free_choice_takes_the_first_option() -> None:
    c = beside("knife", "plate", "beside")
    assert choose([], [c]) == Resolution((R("knife", LEFT, "plate"),), (0,), ("first",))


def test_forced_by_the_definite_relations() -> None:
    definite = [R("fork", RIGHT, "plate"), R("knife", RIGHT, "fork")]
    got = choose(definite, [beside("knife", "plate")])
    assert got == Resolution((R("knife", RIGHT, "plate"),), (1,), ("forced",))


def test_decided_by_a_hint_either_way_round() -> None:
    c = beside("knife", "plate")
    said = R("knife", RIGHT, "plate")
    assert choose([], [c], [said]) == Resolution((said,), (1,), ("hint",))
    # The LLM may say it from the plate's side: the plate to the left of the knife.
    assert choose([], [c], [R("plate", LEFT, "knife")]) == Resolution((said,), (1,), ("hint",))
    # A hint about something else decides nothing.
    assert choose([], [c], [R("cup", RIGHT, "plate")]).why == ("first",)


def test_a_hint_that_cannot_hold_gives_way() -> None:
    definite = [R("fork", LEFT, "plate"), R("knife", LEFT, "fork")]
    got = choose(definite, [beside("knife", "plate")], [R("knife", RIGHT, "plate")])
    assert got == Resolution((R("knife", LEFT, "plate"),), (0,), ("forced",))


def test_either_side_of() -> None:
    c = either_side("fork", "knife", "plate")
    assert choose([], [c]).picked == (0,)
    got = choose([R("knife", LEFT, "fork")], [c])
    assert got == Resolution((R("fork", RIGHT, "plate"), R("knife", LEFT, "plate")), (1,),
                             ("forced",))
    # One hint on either relation of an option is enough, said either way round.
    assert choose([], [c], [R("plate", RIGHT, "knife")]) == Resolution(
        c.options[1], (1,), ("hint",))


def test_earlier_choices_decide_first_and_hints_outweigh_order() -> None:
    # With the cup right of the plate: the knife left of the plate puts the cup right of
    # the knife, while the knife right of the plate leaves the cup either side of it.
    definite = [R("cup", RIGHT, "plate")]
    choices = [beside("knife", "plate"), beside("cup", "knife")]
    got = choose(definite, choices)
    assert got.picked == (0, 1)
    assert got.why == ("first", "first")  # the cup left of the knife holds in (1, 0)
    assert got.relations == (R("knife", LEFT, "plate"), R("cup", RIGHT, "knife"))
    hinted = choose(definite, choices, [R("cup", LEFT, "knife")])
    assert hinted.picked == (1, 0)
    assert hinted.why == ("first", "hint")


def test_conflict_is_a_minimal_set_of_units() -> None:
    definite = [R("cup", ABOVE, "plate", "1"), R("knife", ABOVE, "plate", "2"),
                R("fork", LEFT, "plate", "3")]
    choices = [either_side("fork", "spoon", "bowl"), beside("knife", "plate", "beside"),
               beside("cup", "bowl")]
    got = choose(definite, choices)
    assert got == Resolution((), (), (), (definite[1], choices[1]))
    assert not got.consistent
    # Every proper subset of the conflict holds: each unit alone does.
    assert choose([definite[1]], []).consistent and choose([], [choices[1]]).consistent


def test_conflict_needing_two_choices() -> None:
    # Either option of ``a`` puts the fork right of the plate's column, either option of
    # ``b`` the knife left of it: together, the fork cannot be left of the knife.
    definite = [R("fork", LEFT, "knife")]
    a = Choice(((R("fork", RIGHT, "plate"),), (R("fork", "above and to the right of", "plate"),)))
    b = Choice(((R("knife", LEFT, "plate"),), (R("knife", "below and to the left of", "plate"),)))
    assert choose(definite, [a, b]).conflict == (definite[0], a, b)
    assert choose(definite, [a]).consistent and choose(definite, [b]).consistent
    assert choose([], [a, b]).consistent


def test_no_choices_is_check() -> None:
    good = [R("fork", LEFT, "plate")]
    bad = [R("a", LEFT, "b", "1"), R("a", RIGHT, "b", "2")]
    assert choose(good, []) == Resolution((), (), (), ())
    assert choose(bad, []) == Resolution((), (), (), check(bad).conflict)
    assert choose([], []) == Resolution((), (), (), ())


def test_deterministic() -> None:
    definite = [R("cup", RIGHT, "plate")]
    choices = [beside("knife", "plate"), either_side("fork", "spoon", "plate"),
               beside("cup", "knife")]
    first = choose(definite, choices, [R("spoon", LEFT, "plate")])
    assert all(choose(definite, choices, [R("spoon", LEFT, "plate")]) == first
               for _ in range(5))


def test_choice_needs_options() -> None:
    with pytest.raises(ValueError):
        Choice(())
    with pytest.raises(ValueError):
        Choice(((),))
    # Lists are kept as tuples, so that a choice is hashable.
    c = Choice([[R("a", LEFT, "b")]])  # type: ignore[list-item]
    assert c.options == ((R("a", LEFT, "b"),),) and hash(c)


# --- Brute force ----------------------------------------------------------------------


def _agrees(option: Sequence[Relation], hints: Sequence[Relation]) -> bool:
    keys = {h.key() for h in hints}
    return any(r.key() in keys or (r.reference is not None and r.converse().key() in keys)
               for r in option)


def _holds(definite: Sequence[Relation], choices: Sequence[Choice],
           picks: Sequence[int]) -> bool:
    rels = [*definite, *(r for c, j in zip(choices, picks, strict=True) for r in c.options[j])]
    return check(rels).consistent


def _units_hold(units: Sequence[Relation | Choice]) -> bool:
    definite = [u for u in units if isinstance(u, Relation)]
    choices = [u for u in units if isinstance(u, Choice)]
    return any(_holds(definite, choices, picks)
               for picks in itertools.product(*(range(len(c.options)) for c in choices)))


_OBJECTS = st.sampled_from(["o0", "o1", "o2", "o3"])


@st.composite
def _relation(draw: st.DrawFn) -> Relation:
    rel = draw(st.sampled_from(RELATION_NAMES))
    subject = draw(_OBJECTS)
    if rel == "center":
        return R(subject, rel, None)
    return R(subject, rel, draw(_OBJECTS.filter(lambda o: o != subject)))


_CHOICE = st.lists(st.lists(_relation(), min_size=1, max_size=2).map(tuple), min_size=1,
                   max_size=3).map(lambda options: Choice(tuple(options)))


@settings(max_examples=100, deadline=None, derandomize=True)
@given(st.lists(_relation(), max_size=3), st.lists(_CHOICE, min_size=1, max_size=3),
       st.lists(_relation(), max_size=2))
def test_agrees_with_brute_force(definite: list[Relation], choices: list[Choice],
                                 hints: list[Relation]) -> None:
    got = choose(definite, choices, hints)
    selections = [picks for picks in itertools.product(*(range(len(c.options))
                                                         for c in choices))
                  if _holds(definite, choices, picks)]
    if not selections:
        event("no consistent selection")
        assert got.relations == got.picked == got.why == ()
        units: list[Relation | Choice] = [*definite, *choices]
        conflict = list(got.conflict)
        rest = iter(units)
        assert all(any(u == v for v in rest) for u in conflict), "in input order"
        assert not _units_hold(conflict)
        for k in range(len(conflict)):
            assert _units_hold(conflict[:k] + conflict[k + 1:]), "every unit is needed"
        return
    assert got.conflict == ()
    # Most options agreeing with a hint, then the earliest options, choice by choice.
    best = max(selections, key=lambda picks: (
        sum(_agrees(c.options[j], hints) for c, j in zip(choices, picks, strict=True)),
        tuple(-j for j in picks)))
    assert got.picked == best
    assert got.relations == tuple(r for c, j in zip(choices, best, strict=True)
                                  for r in c.options[j])
    for why in got.why:
        event(f"why: {why}")
    for k, (c, j) in enumerate(zip(choices, best, strict=True)):
        if _agrees(c.options[j], hints):
            assert got.why[k] == "hint"
        elif all(picks[k] == j for picks in selections):
            assert got.why[k] == "forced"
        else:
            assert got.why[k] == "first"
