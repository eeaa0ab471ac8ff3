"""Learning a person's way of setting the table from a few example settings, exactly and
without an LLM (issue 42, its first step).

Each diner's setting in each example (an :class:`~.examples.Observation`) is read
(:func:`~.examples.relation_between`, :func:`~.examples.observed_gap_m`) with
the one meaning of each relation (``world/relations.yaml``, tested by
:func:`~llm_grop.arrangement.predicates.pair_relation_holds`): between two objects the one
relation whose axis states hold, or ``on top of`` when one rests on the other (its
``on``). Its gap is measured as the layout sets it (:func:`~.fidelity.axis_gaps_m`,
between bounding boxes). Of the setting's main object (the one the layout would take as
its origin, :func:`~.geometry.choose_origin`) the distance from the diner's edge of the
table is measured as :func:`~.fidelity.edge_gap_m` does.

**Which pairs.** Not every pair: a setting of n objects has n(n-1)/2 pairs, most of them
far apart and of no interest to anyone ("the fork below and to the left of the mug").
Each object is related to one other. An object that rests on another (its ``on``, in some
observation) is related to what it rests on. Any other is related to its *nearest larger
neighbour on the table*: the objects are ranked by footprint (the catalog kind's area,
largest first; ties in the order the examples list them), and its reference is, among the
objects ranked before it that never rest on another and that some observation shows with
it, the nearest one: the smallest median, over the observations showing both, of the
distance between their footprints' bounding boxes. Why:

* people place a small thing from a bigger one ("the fork to the left of the plate") and
  an upper thing from what it rests on ("the lid on the mug", though the lid is larger),
  and that is how the sentences read;
* every tie goes up the ranking or down a stack, and a stack is placed from its bottom,
  so the pairs form a tree rooted at the setting's main object (the largest, the
  layout's origin, which the edge sentence anchors), a big tray on a small coaster
  included: at most n - 1 sentences, from which the layout (:mod:`.geometry`) walks to
  every object, and with no cycle, so they can never contradict each other in clingo,
  whatever subset of the objects a request names;
* a relation to a larger object applies to more requests than one to a small object
  beside it: the mug is placed from the plate, not from the knife it happens to be near,
  so it keeps its place in a request without a knife.

Two objects in one stack that do not rest on each other directly (the lid and the mat
under its mug) are never a pair: their relation follows from the stack.

**What is learned.** An object's relation to its reference is learned when it is the
same in every observation that shows both; its gap is their median (clamped at 0), and
the spread (min to max) is kept. A relation that differs between observations is a
:class:`Contradiction`: reported, not learned, and no farther reference is tried in its
place (the examples disagree about that object, so one report says so). The main
object's distance from the diner's edge is learned from the observations where it is the
main object, since only the layout's origin uses that sentence.

Every sentence is written in the paper's phrasing and read back with the preference
reader (:mod:`.preferences`) before it is kept, so what is learned is exactly what
``--preferences`` will read. Lengths in metres inside, centimetres in sentences.
"""

from __future__ import annotations

import json
import math
import statistics
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import yaml

from llm_grop.arrangement.examples import (
    Example,
    Observation,
    box_distance_m,
    observed_gap_m,
    read_example,
    read_example_file,
    relation_between,
)
from llm_grop.arrangement.fidelity import edge_gap_m
from llm_grop.arrangement.geometry import choose_origin
from llm_grop.arrangement.phrasing import phrase, round_cm
from llm_grop.arrangement.predicates import Footprint, stacked_pairs
from llm_grop.arrangement.preferences import read_edge_preferences
from llm_grop.errors import BadInput
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import CONVERSE, ON_TOP_OF, UNDER

#: The reading of two objects that overlap on both axes without one resting on the other.
OVERLAPPING = "overlapping"


@dataclass(frozen=True)
class Learned:
    """One learned preference.

    ``sentence`` is in the paper's phrasing (what ``--preferences`` reads):
    ``subject relation reference`` with the gap, or, for ``relation`` ``None``, the
    subject's distance from the diner's edge of the table. ``gap_cm`` is the median gap
    (centimetres; ``None`` for stacking) and ``spread_cm`` the smallest and largest seen.
    ``sources`` are the observations it was read from (every one showing its objects).
    """

    sentence: str
    subject: str
    relation: str | None
    reference: str | None
    gap_cm: float | None
    spread_cm: tuple[float, float] | None
    sources: tuple[str, ...]


@dataclass(frozen=True)
class Contradiction:
    """A pair of neighbours whose relation differs between observations: ``readings``
    holds each relation of ``subject`` to ``reference`` seen (or :data:`OVERLAPPING`)
    with the observations it was seen in."""

    subject: str
    reference: str
    readings: tuple[tuple[str, tuple[str, ...]], ...]

    def message(self) -> str:
        """The contradiction in one line."""
        seen = "; ".join(
            f"{relation} {f'the {self.reference}' if k == 0 else 'it'} in {', '.join(sources)}"
            for k, (relation, sources) in enumerate(self.readings))
        return f"the examples disagree on where the {self.subject} goes: {seen}; not learned"


@dataclass(frozen=True)
class Learning:
    """What a few examples teach: the ``sentences`` learned, the ``contradictions``
    between examples (not learned), ``warnings`` (examples or objects left out, one line
    each), and the ``examples`` learned from (those that could be read)."""

    sentences: tuple[Learned, ...]
    contradictions: tuple[Contradiction, ...] = ()
    warnings: tuple[str, ...] = ()
    examples: tuple[str, ...] = ()

    def preference_file(self) -> str:
        """The sentences as a preferences file (YAML ``preferences: [sentence, ...]``), each
        with its spread and sources as a comment, under a header naming the examples and
        saying what was not learned (the contradictions and warnings)."""
        lines = [f"# Preferences learned by `llm-grop learn` from {_count(self.examples)}:",
                 *(f"#   {_flat(e)}" for e in self.examples),
                 "# Each sentence holds in every example that shows its objects; a distance",
                 "# is the median of theirs, and the comment gives the range seen and where."]
        left_out = [*(c.message() for c in self.contradictions), *self.warnings]
        if left_out:
            lines += ["# Not learned:", *(f"#   {_flat(w)}" for w in left_out)]
        lines.append("preferences:" if self.sentences else "preferences: []")
        for s in self.sentences:
            seen = "" if s.spread_cm is None else f"{_range(s.spread_cm)}; "
            lines.append(f"  - {_yaml_scalar(s.sentence)}  # {seen}"
                         f"{_flat(', '.join(s.sources))}")
        return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class _Reading:
    """One observation's reading of a pair, in the pair's canonical orientation."""

    source: str
    relation: str
    gap_m: float | None
    distance_m: float


def learn(examples: Sequence[str | PathLike[str] | Mapping[str, Any]],
          catalog: Catalog) -> Learning:
    """The preferences the ``examples`` teach: files (arrangement or run JSON) or parsed
    documents (named ``example N``).

    With several examples, one that cannot be read is a warning and the rest are still
    learned from; raises :class:`BadInput` when none can (or the only one cannot), and
    when nothing at all is learned.
    """
    if not examples:
        raise BadInput("learn: give at least one example setting")
    read: list[Example] = []
    names: list[str] = []
    refused: list[str] = []
    warnings: list[str] = []
    seen: set[str] = set()
    for k, example in enumerate(examples):
        name = f"example {k + 1}" if isinstance(example, Mapping) else str(example)
        if name in seen:
            warnings.append(f"{name}: given twice; learned from once")
            continue
        seen.add(name)
        try:
            one = read_example(_final(example), catalog, where=name) \
                if isinstance(example, Mapping) else read_example_file(Path(example), catalog)
        except BadInput as exc:
            if len(examples) == 1:
                raise
            refused.append(str(exc))
            warnings.append(f"{exc}; skipped")
            continue
        read.append(one)
        names.append(name)
    if len(refused) == 1 and not read:
        raise BadInput(refused[0])
    if not read:
        raise BadInput(f"none of the {len(refused)} examples is a table setting: "
                       + "; ".join(refused))
    learning = learn_from([o for e in read for o in e.observations], catalog)
    if not learning.sentences:
        why = "; ".join(c.message() for c in learning.contradictions)
        raise BadInput(f"learned nothing from {_count(names)}" + (f": {why}" if why else ""))
    return Learning(learning.sentences, learning.contradictions,
                    (*warnings, *(w for e in read for w in e.warnings), *learning.warnings),
                    tuple(names))


def _final(document: Mapping[str, Any]) -> Mapping[str, Any]:
    """The setting of a parsed document: a run JSON's ``final``, else the document."""
    final = document.get("final")
    return final if isinstance(final, Mapping) else document


def learn_from(observations: Sequence[Observation], catalog: Catalog) -> Learning:
    """The sentences, contradictions and warnings of ``observations`` (the module doc)."""
    order: dict[str, int] = {}
    area: dict[str, float] = {}
    for obs in observations:
        for item in obs.items:
            order.setdefault(item.name, len(order))
            area.setdefault(item.name, item.spec.area)
    rank = {name: k for k, name in enumerate(sorted(order, key=lambda n: (-area[n], order[n])))}
    readings: dict[tuple[str, str], list[_Reading]] = {}
    for obs in observations:
        for key, reading in _pairs(obs, rank):
            readings.setdefault(key, []).append(reading)
    supports = {(p.name, p.on) for obs in observations for p in obs.placements
                if p.on is not None}
    resting = {upper for upper, _ in supports}

    def may_tie(mine: str, other: str) -> bool:
        # A resting object is tied to its support, any other to a larger object on the
        # table: every tie then goes down a stack or up the ranking, so none closes a
        # cycle (a big tray on a small coaster included).
        if mine in resting:
            return (mine, other) in supports
        return other not in resting and rank[other] < rank[mine]

    nearest: dict[str, tuple[tuple[float, int], tuple[str, str]]] = {}
    for key, seen in readings.items():
        for mine, other in (key, key[::-1]):
            if not may_tie(mine, other):
                continue
            how_near = (statistics.median(r.distance_m for r in seen), rank[other])
            if mine not in nearest or how_near < nearest[mine][0]:
                nearest[mine] = (how_near, key)
    warnings: list[str] = []
    contradictions: list[Contradiction] = []
    chosen: list[tuple[tuple[str, str], list[_Reading]]] = []
    for subject, reference in dict.fromkeys(key for _, key in nearest.values()):
        seen = readings[(subject, reference)]
        relations = list(dict.fromkeys(r.relation for r in seen))
        if len(relations) > 1:
            contradictions.append(Contradiction(subject, reference, tuple(
                (rel, tuple(r.source for r in seen if r.relation == rel)) for rel in relations)))
        elif relations == [OVERLAPPING]:
            warnings.append(f"the {subject} and the {reference} overlap in "
                            f"{', '.join(r.source for r in seen)} and neither rests on the "
                            "other; their relation is not learned")
        else:
            chosen.append(((subject, reference), seen))
    sentences = [*_edges(observations, catalog, warnings)]
    # Said in the order the examples list their objects.
    chosen.sort(key=lambda kv: (order[kv[0][0]], order[kv[0][1]]))
    contradictions.sort(key=lambda c: (order[c.subject], order[c.reference]))
    for (subject, reference), seen in chosen:
        learned = _relation_sentence(subject, reference, seen, observations, catalog)
        if learned is None:
            warnings.append(f"cannot phrase the {subject} {seen[0].relation} the {reference} "
                            "so that the preference reader reads it back; not learned")
        else:
            sentences.append(learned)
    return Learning(tuple(sentences), tuple(contradictions), tuple(warnings))


def _pairs(obs: Observation, rank: Mapping[str, int]
           ) -> list[tuple[tuple[str, str], _Reading]]:
    """Every candidate pair of ``obs`` (see the module doc), keyed ``(subject, reference)``:
    the reference is the one ranked first (``rank``, 0 first)."""
    places = {p.name: p for p in obs.placements}
    direct = {frozenset((p.name, p.on)) for p in obs.placements if p.on is not None}
    chained = stacked_pairs((p.name, p.on) for p in obs.placements if p.on is not None)
    out = []
    names = [it.name for it in obs.items]
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            pair = frozenset((a, b))
            if pair in chained and pair not in direct:
                continue
            reference, subject = sorted((a, b), key=lambda n: rank[n])
            s, r = places[subject], places[reference]
            relation = relation_between(s, r)
            gap = None if relation is None or relation in (ON_TOP_OF, UNDER) \
                else observed_gap_m(relation, s, r)
            out.append(((subject, reference), _Reading(
                obs.source, relation or OVERLAPPING, gap,
                0.0 if pair in direct else box_distance_m(s, r))))
    return out


def _edges(observations: Sequence[Observation], catalog: Catalog,
           warnings: list[str]) -> list[Learned]:
    """The main object's distance from the diner's edge, per object that is the main one
    in some observation, learned from those observations."""
    seen: dict[str, list[tuple[str, float, Observation]]] = {}
    for obs in observations:
        main = choose_origin(obs.items, ())
        p = next(p for p in obs.placements if p.name == main)
        gap = float(edge_gap_m(p.y, Footprint.of_placement(p), obs.place))
        seen.setdefault(main, []).append((obs.source, gap, obs))
    out = []
    for main, gaps in seen.items():
        cm = [100 * g for _, g, _ in gaps]
        median = round_cm(max(statistics.median(cm), 0.0))
        sentence = f"the {main} {median:g} cm from the diner's edge of the table"
        first = gaps[0][2]
        try:
            read = read_edge_preferences([sentence], [], first.items, catalog, first.place)
        except BadInput:
            read = {}
        if set(read) != {main} or not math.isclose(read[main], median / 100):
            warnings.append(f"cannot phrase {sentence!r} so that the preference reader "
                            "reads it back; not learned")
            continue
        out.append(Learned(sentence, main, None, None, median,
                           (round_cm(min(cm)), round_cm(max(cm))),
                           tuple(source for source, _, _ in gaps)))
    return out


def _relation_sentence(subject: str, reference: str, seen: Sequence[_Reading],
                       observations: Sequence[Observation], catalog: Catalog
                       ) -> Learned | None:
    """The learned sentence of a pair whose every reading is the same relation, phrased so
    that the preference reader reads it back exactly; ``None`` when no phrasing does."""
    relation = seen[0].relation
    if relation == UNDER:  # said from the upper object, as people say it
        subject, reference, relation = reference, subject, CONVERSE[UNDER]
    sources = tuple(r.source for r in seen)
    first = next(o for o in observations if o.source == sources[0])
    gap_cm, spread = None, None
    if relation != ON_TOP_OF:
        cm = [100 * r.gap_m for r in seen if r.gap_m is not None]
        gap_cm = round_cm(max(statistics.median(cm), 0.0))
        spread = (round_cm(min(cm)), round_cm(max(cm)))
    sentence = phrase(subject, relation, reference, gap_cm, first.items, catalog)
    return None if sentence is None else \
        Learned(sentence, subject, relation, reference, gap_cm, spread, sources)


def _range(spread_cm: tuple[float, float]) -> str:
    low, high = spread_cm
    return f"{low:g} cm" if low == high else f"{low:g} to {high:g} cm"


def _count(names: Sequence[str]) -> str:
    return f"{len(names)} example" + ("" if len(names) == 1 else "s")


def _flat(text: str) -> str:
    """``text`` on one line, for a YAML comment."""
    return " ".join(text.split())


def _yaml_scalar(text: str) -> str:
    """``text`` as a YAML list entry's scalar: plain when YAML reads it back as it is,
    else double-quoted (a JSON string is a YAML one)."""
    try:
        plain = yaml.safe_load(f"- {text}") == [text] and "#" not in text
    except yaml.YAMLError:
        plain = False
    return text if plain else json.dumps(text, ensure_ascii=False)
