"""One meaning of each relation: the table ``world/relations.yaml``, and its three readers.

The table's invariants and the checks its loader makes; that ``relations.lp`` holds no
relation-specific rule (clingo learns every meaning from facts generated from the table);
that the geometric predicates read the same states; and a property: every set of
relations clingo accepts is either realised by the guided layout and the sampler, every
configuration keeping every relation, or refused as infeasible with a reason that names
what failed.
"""

from __future__ import annotations

import re
from importlib import resources

import numpy as np
import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st

from llm_grop.arrangement import consistency, geometry, sampling
from llm_grop.arrangement.predicates import Footprint, pair_relation_holds
from llm_grop.errors import Infeasible
from llm_grop.world import relation as rel
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import MEANINGS, RELATION_NAMES, Relation, parse_meanings
from llm_grop.world.request import items_from_names
from llm_grop.world.table import Table

TABLE_TEXT = resources.files("llm_grop.world").joinpath("relations.yaml").read_text("utf-8")
LP_TEXT = resources.files("llm_grop.arrangement").joinpath("relations.lp").read_text("utf-8")


def test_names_and_order_are_the_contracts() -> None:
    assert RELATION_NAMES == (
        "above", "to the right of", "below", "to the left of", "above and to the right of",
        "below and to the right of", "below and to the left of", "above and to the left of",
        "on top of", "under", "center")
    assert (rel.LEFT, rel.RIGHT, rel.ABOVE, rel.BELOW, rel.ON_TOP_OF, rel.UNDER, rel.CENTER) \
        == ("to the left of", "to the right of", "above", "below", "on top of", "under",
            "center")
    assert (rel.ABOVE_LEFT, rel.ABOVE_RIGHT, rel.BELOW_LEFT, rel.BELOW_RIGHT) == (
        "above and to the left of", "above and to the right of", "below and to the left of",
        "below and to the right of")


def test_derived_names_follow_the_table() -> None:
    sign = {"less": -1, "aligned": 0, "greater": 1}
    with_reference = [m for m in MEANINGS.values() if m.reference]
    assert {m.name: (sign[m.state("x")], sign[m.state("y")])
                             for m in with_reference} == rel.DIRECTION
    assert {m.name: m.converse for m in with_reference} == rel.CONVERSE
    assert {m.name for m in MEANINGS.values() if m.rests is not None} == rel.STACKING
    assert {m.name: m.asp for m in MEANINGS.values()} == rel.ASP_NAME
    assert consistency.ASP_NAME is rel.ASP_NAME
    assert [m.name for m in MEANINGS.values() if not m.reference] == [rel.CENTER]


def test_table_invariants() -> None:
    mirror = {"less": "greater", "aligned": "aligned", "greater": "less"}
    swap = {"subject": "reference", "reference": "subject", None: None}
    assert len(set(rel.ASP_NAME.values())) == len(RELATION_NAMES)
    assert all(re.fullmatch(r"[a-z][a-z0-9_]*", a) for a in rel.ASP_NAME.values())
    meanings = [(m.x, m.y, m.rests) for m in MEANINGS.values()]
    assert len(set(meanings)) == len(meanings), "one meaning per relation"
    for m in MEANINGS.values():
        if not m.reference:
            assert (m.x, m.y, m.rests, m.converse) == (None, None, None, None)
            continue
        c = MEANINGS[m.converse or ""]
        assert c.converse == m.name
        assert (c.x, c.y, c.rests) == (mirror[m.state("x")], mirror[m.state("y")],
                                       swap[m.rests])
        if m.rests is not None:
            assert (m.x, m.y) == ("aligned", "aligned")


BROKEN = {
    "converse not symmetric": (
        "y: aligned, converse: to the right of}", "y: aligned, converse: above}",
        "the converse of 'to the left of' is 'above', not 'to the right of'"),
    "states not mirrored": (
        "{name: below,                     asp: below,       x: aligned, y: less,",
        "{name: below,                     asp: below,       x: aligned, y: aligned,",
        "must mirror its states"),
    "a name twice": ("name: under,", "name: on top of,", "the name is used twice"),
    "a constant twice": ("asp: under,", "asp: on_top_of,", "'on_top_of' is used twice"),
    "a constant that is not one": ("asp: left,", "asp: Left,", "lowercase identifier"),
    "an unknown state": ("x: less,    y: aligned", "x: lesser,  y: aligned", "expected one of"),
    "resting but apart": ("x: aligned, y: aligned, rests: subject",
                          "x: less, y: aligned, rests: subject", "aligned on both axes"),
    "an unknown field": ("asp: center,", "asp: center, size: 1,", "unknown field 'size'"),
    "two meanings alike": ("x: less,    y: less,", "x: less,    y: greater,",
                           "means the same as"),
    "center with a state": ("asp: center,", "asp: center, x: less,", "has none"),
    "center with a converse": ("reference: false}", "reference: false, converse: under}",
                               "has none"),
    "no relation without a reference": (
        "  - {name: center,                    asp: center,      reference: false}", "",
        "exactly one relation must be without a reference"),
}


@pytest.mark.parametrize(("old", "new", "message"), BROKEN.values(), ids=BROKEN.keys())
def test_a_broken_table_is_refused(old: str, new: str, message: str) -> None:
    assert old in TABLE_TEXT
    with pytest.raises(ValueError, match=re.escape(message)):
        parse_meanings(TABLE_TEXT.replace(old, new, 1), "test table")


def test_broken_yaml_is_refused() -> None:
    with pytest.raises(ValueError, match="test table: not valid YAML"):
        parse_meanings("relations: [", "test table")
    with pytest.raises(ValueError, match="'relations' list"):
        parse_meanings("relations: []", "test table")


def test_relations_lp_has_no_relation_specific_rule() -> None:
    code = "\n".join(line.split("%", 1)[0] for line in LP_TEXT.splitlines())
    for name, asp in rel.ASP_NAME.items():
        for word in (asp, name):
            assert not re.search(rf"(?<![A-Za-z0-9_]){word}(?![A-Za-z0-9_])", code), word


def test_asp_facts_are_the_table() -> None:
    facts = set(consistency._table_facts().splitlines())
    expected = set()
    for m in MEANINGS.values():
        if m.converse is None:
            continue
        expected |= {f"axis({m.asp},x,{m.x}).", f"axis({m.asp},y,{m.y}).",
                     f"converse({m.asp},{MEANINGS[m.converse].asp})."}
        if m.rests is not None:
            expected.add(f"rests({m.asp},{m.rests}).")
    assert facts == expected


def test_clingo_and_the_predicates_read_the_same_states() -> None:
    """For every relation and every subject state per axis, half a metre apart on a strict
    axis: the predicate holds exactly in the table's states, and clingo accepts the
    relation together with the relation read off that placement exactly then."""
    small, large = Footprint("box", 0.02, 0.03), Footprint("circle", 0.05, 0.05)
    read_off = {d: name for name, d in rel.DIRECTION.items() if name not in rel.STACKING}
    for name, meaning in MEANINGS.items():
        if not meaning.reference:
            continue
        for sx in (-1, 0, 1):
            for sy in (-1, 0, 1):
                holds = bool(pair_relation_holds(name, 0.5 * sx, 0.5 * sy, small, 0.0, 0.0,
                                                 large))
                expected = (sx, sy) == meaning.direction
                assert holds == expected, (name, sx, sy)
                if (sx, sy) == (0, 0):
                    continue  # a pair at one point: only stacking says it, checked above
                seen = Relation("a", read_off[(sx, sy)], "b")
                ok = consistency.check([Relation("a", name, "b"), seen]).consistent
                assert ok == expected, (name, seen.relation)


# --- Accepted by clingo, realised or refused by the sampler -------------------------------

CATALOG = Catalog.load(use_env=False)
KINDS = sorted(CATALOG.names())

#: Configurations sampled per accepted set.
M = 3


@st.composite
def _settings(draw: st.DrawFn) -> tuple[list[str], list[Relation], Table, float | None]:
    kinds = draw(st.lists(st.sampled_from(KINDS), min_size=2, max_size=5))
    names = [it.name for it in items_from_names(kinds, CATALOG)]
    rels = []
    for _ in range(draw(st.integers(1, 6))):
        r = draw(st.sampled_from(RELATION_NAMES))
        s = draw(st.integers(0, len(names) - 1))
        o = (s + draw(st.integers(1, len(names) - 1))) % len(names)
        rels.append(Relation(names[s], r, None if r == rel.CENTER else names[o]))
    if draw(st.booleans()) and draw(st.booleans()):
        table = Table.circle(draw(st.floats(0.5, 1.6)))
    else:
        table = Table(draw(st.floats(0.5, 2.0)), draw(st.floats(0.4, 1.2)))
    edge = draw(st.none() | st.floats(0.0, table.depth / 2))
    return kinds, rels, table, edge


@settings(max_examples=1000, deadline=None, derandomize=True)
@given(_settings(), st.lists(st.sampled_from([0.01, 0.02, 0.03, 0.05, 0.08]), min_size=6,
                             max_size=6), st.integers(0, 2**32 - 1))
def test_accepted_sets_are_realised_or_refused_with_a_reason(
        setting: tuple[list[str], list[Relation], Table, float | None], gaps: list[float],
        seed: int) -> None:
    kinds, rels, table, edge = setting
    if not consistency.check(rels).consistent:
        event("refused by clingo")
        return
    event("accepted by clingo")
    items = items_from_names(kinds, CATALOG)
    gaps_m = {r.key(): g for r, g in zip(rels, gaps, strict=False)
              if r.relation != rel.CENTER and r.relation not in rel.STACKING}
    # As the pipeline does (pipeline.sample_setting): the stated gaps within the fidelity
    # tolerance first, and without that tolerance when nothing keeps them.
    try:
        layout = geometry.guided_layout(items, rels, gaps_m, table, edge,
                                        geometry.choose_origin(items, rels))
        try:
            configs = sampling.sample_configurations(items, layout, rels, table,
                                                     np.random.default_rng(seed), m=M,
                                                     gaps_m=gaps_m)
        except Infeasible:
            configs = sampling.sample_configurations(items, layout, rels, table,
                                                     np.random.default_rng(seed), m=M,
                                                     gaps_m=gaps_m, tolerance_m=None)
    except Infeasible as exc:
        reason = str(exc)
        event("refused: " + ("the table is too small" if "too small" in reason
                             else "the sampler found too few"))
        assert reason.startswith("no feasible arrangement")
        assert any(it.name in reason for it in items), reason
        return
    event("realised")
    assert len(configs) == M
    for config in configs:
        assert sampling.violations(config, rels, table) == []


def test_what_only_sizes_forbid_is_refused_with_a_reason() -> None:
    """clingo knows no sizes: a plate and a bowl both resting on a mug mat are consistent
    (two objects on one support), and only the sampler finds they cannot both fit."""
    items = items_from_names(["dinner plate", "fruit bowl", "mug mat"], CATALOG)
    rels = [Relation("dinner plate", rel.ON_TOP_OF, "mug mat"),
            Relation("fruit bowl", rel.ON_TOP_OF, "mug mat")]
    table = Table(0.9, 0.6)
    assert consistency.check(rels).consistent
    layout = geometry.guided_layout(items, rels, {}, table)
    with pytest.raises(Infeasible, match="fruit bowl overlaps dinner plate"):
        sampling.sample_configurations(items, layout, rels, table, np.random.default_rng(0),
                                       m=M)
