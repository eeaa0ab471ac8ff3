"""From relations to a setting: what the request and the preferences state, how an
ambiguous stated relation is decided, and the gaps (Template 2) and the diner's distance
that ground the relations (paper §III-B)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from llm_grop import seeds
from llm_grop.arrangement import consistency, distances, geometry, preferences
from llm_grop.arrangement.options import ArrangeOptions
from llm_grop.arrangement.setting import Attempt, Setting
from llm_grop.errors import BadInput, ReplayMissing
from llm_grop.llm.base import CallLog
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import CENTER, STACKING, Choice, Relation
from llm_grop.world.table import Table


@dataclass(frozen=True)
class Stated:
    """What the request and the preferences state about one setting's objects: definite
    relations (``relations``, which win over the LLM's) and ambiguous ones (``choices``)."""

    relations: tuple[Relation, ...]
    choices: tuple[Choice, ...]


def stated_for(items: Sequence[Item], options: ArrangeOptions, catalog: Catalog) -> Stated:
    """The stated relations about ``items``; :class:`BadInput` when they contradict each
    other."""
    names = {it.name for it in items}

    def ours(rels: Sequence[Relation]) -> bool:
        return all(r.subject in names and (r.reference is None or r.reference in names)
                   for r in rels)

    said = [r for r in options.stated if ours([r])]
    learned = dict(options.learned)
    read = preferences.read_preferences(options.preferences,
                                        (*options.preference_pool, *learned), items, catalog,
                                        learned)
    prefs = preferences.combine(said, read.relations)
    choices = tuple(c for c in (*options.choices, *read.choices)
                    if all(ours(option) for option in c.options))
    conflict = consistency.choose(prefs, choices).conflict if choices else ()
    if conflict:
        raise BadInput(preferences.contradiction(conflict))
    return Stated(tuple(prefs), choices)


@dataclass(frozen=True)
class Grounding:
    """How to ground one setting: the LLM and the options it is asked with, the run's
    seed, and where to say what happens."""

    llm: CallLog
    catalog: Catalog
    seed: int
    options: ArrangeOptions
    say: Callable[[str], None]


def ground(items: Sequence[Item], accepted: Sequence[Relation], stated: Stated, table: Table,
           g: Grounding, *, attempts: Sequence[Attempt] = (),
           dropped: Sequence[Relation] = (), warnings: Sequence[str] = (),
           known: Setting | None = None) -> Setting:
    """The setting of ``items`` on a place of ``table``'s size from the LLM's ``accepted``
    relations and the ``stated`` ones (which win): the ambiguous stated relations decided,
    the gaps (Template 2) and the origin's distance from the diner's edge. ``known``: an
    earlier setting of the same objects whose gaps and distance are kept where its
    relations and origin are kept (a revision asks only about what changed)."""
    notes = list(warnings)
    prefs: tuple[Relation, ...] = stated.relations
    if stated.choices:
        decided = consistency.choose(prefs, stated.choices, hints=accepted)
        prefs = (*prefs, *decided.relations)
        notes += [_decided(c, c.options[k], why) for c, k, why
                  in zip(stated.choices, decided.picked, decided.why, strict=True)]
    kept = tuple(accepted)
    if prefs:
        kept, overridden = preferences.merge(prefs, kept)
        said = {r.key() for r in prefs} | {r.converse().key() for r in prefs
                                            if r.reference is not None}
        notes += [f"overridden by a stated relation: {preview(r.line or r.sentence())}"
                  for r in overridden if r.key() not in said]
    related = {r.subject for r in kept} | {r.reference for r in kept}
    notes += [f"no usable relation for the {it.name}: the answers left it out, so "
              f"the sampler places it alone" for it in items
              if len(items) > 1 and it.name not in related]
    gaps: dict[tuple[str, str, str | None], float] = {}
    stated_gap = preferences.stated_gaps(prefs, table)
    for k, rel in enumerate(kept):
        if rel.relation == CENTER or rel.relation in STACKING:
            continue
        if rel.key() in stated_gap:
            gaps[rel.key()] = stated_gap[rel.key()]
            continue
        if known is not None and rel.key() in known.gaps:
            gaps[rel.key()] = known.gaps[rel.key()]
            continue
        g.say(f"asking {g.llm.model} for the distance: {rel.sentence()}")
        record = g.llm.complete(distances.template2_prompt(rel),
                                g.options.params.with_seed(
                                    seeds.int_seed(g.seed, "llm.distance", k)),
                                distances.template2_grammar())
        gaps[rel.key()], defaulted = distances.parse_distance_m(record.response)
        if defaulted:
            notes.append(f"no distance in {preview(record.response)!r}; used "
                         f"{distances.DEFAULT_GAP_CM:g} cm for: {rel.sentence()}")
    origin, edge_gap = _edge_distance(items, kept, table, g, notes, known)
    return Setting(kept, gaps, origin, edge_gap, tuple(attempts), tuple(dropped),
                   tuple(dict.fromkeys(notes)))


def _edge_distance(items: Sequence[Item], accepted: Sequence[Relation], table: Table,
                   g: Grounding, warnings: list[str], known: Setting | None
                   ) -> tuple[str, float]:
    """The layout's origin and its distance, metres, from the diner's edge: a preference's,
    else ``known``'s for the same origin, else the LLM's answer, else
    :data:`~llm_grop.arrangement.distances.DEFAULT_EDGE_GAP_CM`."""
    options = g.options
    edges = preferences.read_edge_preferences(
        options.preferences, (*options.preference_pool, *(s for s, _ in options.learned)),
        items, g.catalog, table)
    origin = geometry.choose_origin(items, accepted, anchored=edges)
    warnings += [f"unused: a distance from the diner's edge applies to the origin "
                 f"({origin}), not to {name}" for name in edges if name != origin]
    if origin in edges:
        return origin, edges[origin]
    if known is not None and known.origin == origin:
        return origin, known.edge_gap_m
    g.say(f"asking {g.llm.model} for the distance of the {origin} from the diner's edge")
    try:
        answer = g.llm.complete(distances.edge_prompt(origin),
                                options.params.with_seed(seeds.int_seed(g.seed, "llm.edge", 0)),
                                distances.template2_grammar()).response
    except ReplayMissing:
        # Recordings made before llm-grop asked this question still replay.
        warnings.append(f"the replayed recording has no answer to the diner's-edge question "
                        f"(recorded before llm-grop 0.4); used "
                        f"{distances.DEFAULT_EDGE_GAP_CM:g} cm for the {origin}")
        return origin, distances.DEFAULT_EDGE_GAP_CM / 100
    edge_gap, defaulted = distances.parse_distance_m(answer, distances.DEFAULT_EDGE_GAP_CM)
    if edge_gap > table.depth / 2:
        warnings.append(f"{100 * edge_gap:g} cm from the diner's edge is beyond the middle "
                        f"of the {table.depth:g} m deep place; used "
                        f"{distances.DEFAULT_EDGE_GAP_CM:g} cm for the {origin}")
        edge_gap = distances.DEFAULT_EDGE_GAP_CM / 100
    elif defaulted:
        warnings.append(f"no distance in {preview(answer)!r}; used "
                        f"{distances.DEFAULT_EDGE_GAP_CM:g} cm from the diner's edge "
                        f"for the {origin}")
    return origin, edge_gap


_WHY = {"hint": "as the LLM's relations have it",
        "forced": "the only way the other relations allow",
        "first": "the first way that fits the other relations; nothing said which"}


def _decided(choice: Choice, option: Sequence[Relation], why: str) -> str:
    """The warning that says how an ambiguous stated relation was decided, and why."""
    said = "; ".join(f"the {r.subject} {r.relation} the {r.reference}" for r in option)
    return f"{choice.words or 'an ambiguous relation'!r} read as {said} ({_WHY[why]})"


def preview(answer: str, limit: int = 120) -> str:
    """An LLM answer shortened for a warning: one line of at most ``limit`` characters."""
    text = " ".join(answer[:4 * limit].split())
    return text if len(text) <= limit else text[:limit - 1] + "…"
