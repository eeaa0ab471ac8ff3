"""The semantic arrangement pipeline (paper §III-A and §III-B).

request items -> Template 1 -> parsed relations (+ follow-ups for left-out objects)
-> clingo consistency check (re-prompt with a new seed on conflict, bounded)
-> Template 2 distances, and the origin object's distance from the diner's edge
-> LLM-guided positions -> M sampled configurations, each measured for fidelity.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from shapely.geometry import Polygon

from llm_grop import seeds
from llm_grop.arrangement import (
    consistency,
    diners,
    distances,
    fidelity,
    geometry,
    preferences,
    relations,
    sampling,
)
from llm_grop.arrangement.layout import GuidedLayout
from llm_grop.arrangement.setting import Attempt, Sampled, Setting
from llm_grop.errors import BadInput, Infeasible, LLMAnswerUnusable, ReplayMissing
from llm_grop.language.answer_reader import parse_relations
from llm_grop.llm.base import CallLog, SamplingParams
from llm_grop.settings import DEFAULTS
from llm_grop.world.arrangement import Arrangement, Configuration, Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.fidelity import Fidelity
from llm_grop.world.llmlog import CallRecord, LLMSummary
from llm_grop.world.relation import CENTER, STACKING, Choice, Relation
from llm_grop.world.request import Request
from llm_grop.world.table import Table

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ArrangeOptions:
    """Settings of :func:`arrange_items`.

    ``m``: configurations to sample. ``max_attempts``: Template 1 prompts before
    giving up on a fully consistent answer (the first one included).
    ``examples``: the few-shot block of Template 1 (``None``: the paper's
    examples; ``""``: zero-shot). ``notes``: Template 1's [notes] slot.
    ``reprompt_temperature_step``: added to the temperature at each re-prompt
    (capped at 1.0), because at the paper's 0.1 a new seed alone rarely changes
    the answer. ``gap_tolerance_m``: every configuration keeps each stated gap and the
    diner's distance within this many metres (``None``: no such check; see
    :mod:`llm_grop.arrangement.fidelity`). ``stated``: relations the request states
    between its objects (``source="request"``, first diner's names); they take the
    preferences' precedence. ``choices``: the ambiguous ones ("the knife beside the plate"),
    decided by the LLM's relations or clingo (:func:`~llm_grop.arrangement.consistency.choose`).
    """

    m: int = DEFAULTS.m
    max_attempts: int = DEFAULTS.attempts
    examples: str | None = None
    notes: str = ""
    params: SamplingParams = field(default_factory=SamplingParams)
    reprompt_temperature_step: float = 0.3
    preferences: tuple[str, ...] = ()
    preference_pool: tuple[str, ...] = ()
    gap_tolerance_m: float | None = fidelity.GAP_TOLERANCE_M
    stated: tuple[Relation, ...] = ()
    choices: tuple[Choice, ...] = ()


@dataclass(frozen=True)
class ArrangementResult:
    """Everything :func:`arrange_items` found.

    ``arrangement`` holds the first configuration; ``configurations`` all M of
    them (the planner chooses among these); ``dropped`` the LLM lines left out
    to restore consistency; ``gaps_m`` the stated gaps by relation key; ``edge_gap_m``
    the origin's stated distance from the diner's edge; ``fidelity`` one measure per
    configuration.
    """

    arrangement: Arrangement
    configurations: tuple[Configuration, ...]
    layout: GuidedLayout
    attempts: tuple[Attempt, ...]
    dropped: tuple[Relation, ...]
    gaps_m: dict[tuple[str, str, str | None], float]
    edge_gap_m: float | None = None
    fidelity: tuple[Fidelity, ...] = ()


def _dedupe(rels: Sequence[Relation]) -> list[Relation]:
    """Drops repeats of a fact, also when restated as its converse."""
    seen: set[tuple[str, str, str | None]] = set()
    out = []
    for r in rels:
        if r.key() in seen:
            continue
        seen.add(r.key())
        if r.reference is not None:
            seen.add(r.converse().key())
        out.append(r)
    return out


def _anchor_for(missing: str, items: Sequence[Item], rels: Sequence[Relation]) -> str:
    """The object a follow-up asks about: the centre object, else the largest other item."""
    for r in rels:
        if r.relation == CENTER and r.subject != missing:
            return r.subject
    others = [it for it in items if it.name != missing]
    return max(others, key=lambda it: it.spec.area).name


def _ask_relations(items: Sequence[Item], llm: CallLog, catalog: Catalog, seed: int,
                   attempt: int, options: ArrangeOptions) -> Attempt:
    kwargs = {} if options.examples is None else {"examples": options.examples}
    prompt = relations.template1_prompt(items, notes=options.notes, **kwargs)
    s = seeds.int_seed(seed, "llm.relations", attempt)
    temperature = min(1.0, options.params.temperature + attempt * options.reprompt_temperature_step)
    params = replace(options.params, seed=s, temperature=max(temperature,
                                                               options.params.temperature))
    record = llm.complete(prompt, params, relations.template1_grammar(items))
    parsed = parse_relations(record.response, items, catalog)
    found = list(parsed.relations)
    # Template 1 asks for one relation per pair; an ambiguous line ("beside") is none.
    ignored = list(parsed.ignored) + [c.words for c in parsed.choices]
    if len(items) > 1:
        for k, missing in enumerate(parsed.missing):
            anchor = _anchor_for(missing, items, found)
            record = llm.complete(
                relations.followup_prompt(missing, anchor),
                options.params.with_seed(seeds.int_seed(seed, "llm.followup", attempt, k)),
                relations.followup_grammar(missing, anchor))
            answer = parse_relations(record.response, items, catalog)
            found += [r for r in answer.relations if missing in (r.subject, r.reference)]
            ignored += list(answer.ignored) + [c.words for c in answer.choices]
    found = _dedupe(found)
    report = consistency.check(found)
    return Attempt(s, tuple(found), report.conflict, tuple(ignored))


def _choose_relations(attempts: Sequence[Attempt]) -> tuple[tuple[Relation, ...], list[Relation]]:
    """The relations to keep once every attempt conflicted: the largest consistent subset."""
    best: tuple[Relation, ...] = ()
    best_source: tuple[Relation, ...] = ()
    for a in attempts:
        subset = consistency.largest_consistent_subset(a.relations)
        if len(subset) > len(best):
            best, best_source = subset, a.relations
    kept = {r.key() for r in best}
    return best, [r for r in best_source if r.key() not in kept]


def _symbolic(items: Sequence[Item], llm: CallLog, catalog: Catalog, table: Table, seed: int,
              options: ArrangeOptions, say: Callable[[str], None]) -> Setting:
    """Relations (Template 1, preferences, clingo), gaps (Template 2) and the diner's
    distance for one setting of ``items`` on a place of ``table``'s size."""
    warnings: list[str] = []
    attempts: list[Attempt] = []
    accepted: tuple[Relation, ...] = ()
    dropped: list[Relation] = []
    names = {it.name for it in items}

    def ours(rels: Sequence[Relation]) -> bool:
        return all(r.subject in names and (r.reference is None or r.reference in names)
                   for r in rels)

    stated = [r for r in options.stated if ours([r])]
    read = preferences.read_preferences(options.preferences, options.preference_pool, items,
                                        catalog)
    prefs = preferences.combine(stated, read.relations)
    choices = [c for c in (*options.choices, *read.choices)
               if all(ours(option) for option in c.options)]
    conflict = consistency.choose(prefs, choices).conflict if choices else ()
    if conflict:
        raise BadInput(preferences.contradiction(conflict))
    if preferences.covers(prefs, items):
        say("the stated relations relate every object: Template 1 is not asked")
    elif len(items) > 1:
        for k in range(options.max_attempts):
            say(f"asking {llm.model} for symbolic relations "
                f"(attempt {k + 1}/{options.max_attempts})")
            attempt = _ask_relations(items, llm, catalog, seed, k, options)
            attempts.append(attempt)
            if attempt.conflict:
                log.info("attempt %d conflicts: %s", k + 1,
                         "; ".join(r.line or r.sentence() for r in attempt.conflict))
            if attempt.consistent:
                accepted = attempt.relations
                break
        else:
            accepted, dropped = _choose_relations(attempts)
            if not accepted:
                last = attempts[-1] if attempts else None
                detail = f"; last answer had {len(last.relations)} relation(s)" if last else ""
                raise LLMAnswerUnusable(
                    f"{llm.backend} LLM gave no usable spatial relation in "
                    f"{options.max_attempts} attempt(s){detail}")
            warnings += [f"dropped to restore consistency: {_preview(r.line or r.sentence())}"
                         for r in dropped]
        for attempt in attempts:
            warnings += [f"ignored LLM line: {line}" for line in attempt.ignored if line]
    if choices:
        decided = consistency.choose(prefs, choices, hints=accepted)
        prefs = (*prefs, *decided.relations)
        warnings += [_decided(c, c.options[k], why) for c, k, why
                     in zip(choices, decided.picked, decided.why, strict=True)]
    if prefs:
        accepted, overridden = preferences.merge(prefs, accepted)
        said = {r.key() for r in prefs} | {r.converse().key() for r in prefs
                                            if r.reference is not None}
        warnings += [f"overridden by a stated relation: {_preview(r.line or r.sentence())}"
                     for r in overridden if r.key() not in said]
    related = {r.subject for r in accepted} | {r.reference for r in accepted}
    warnings += [f"no usable relation for the {it.name}: the answers left it out, so "
                 f"the sampler places it alone" for it in items
                 if len(items) > 1 and it.name not in related]

    gaps: dict[tuple[str, str, str | None], float] = {}
    stated_gap = preferences.stated_gaps(prefs, table)
    for k, rel in enumerate(accepted):
        if rel.relation == CENTER or rel.relation in STACKING:
            continue
        if rel.key() in stated_gap:
            gaps[rel.key()] = stated_gap[rel.key()]
            continue
        say(f"asking {llm.model} for the distance: {rel.sentence()}")
        record = llm.complete(distances.template2_prompt(rel),
                              options.params.with_seed(seeds.int_seed(seed, "llm.distance", k)),
                              distances.template2_grammar())
        gaps[rel.key()], defaulted = distances.parse_distance_m(record.response)
        if defaulted:
            warnings.append(f"no distance in {_preview(record.response)!r}; used "
                            f"{distances.DEFAULT_GAP_CM:g} cm for: {rel.sentence()}")
    origin, edge_gap = _edge_distance(items, accepted, llm, catalog, table, seed, options, say,
                                      warnings)
    return Setting(accepted, gaps, origin, edge_gap, tuple(attempts), tuple(dropped),
                   tuple(dict.fromkeys(warnings)))


def _edge_distance(items: Sequence[Item], accepted: Sequence[Relation], llm: CallLog,
                   catalog: Catalog, table: Table, seed: int, options: ArrangeOptions,
                   say: Callable[[str], None], warnings: list[str]) -> tuple[str, float]:
    """The layout's origin and its distance, metres, from the diner's edge: a preference's,
    else the LLM's answer, else :data:`~llm_grop.arrangement.distances.DEFAULT_EDGE_GAP_CM`."""
    edges = preferences.read_edge_preferences(options.preferences, options.preference_pool,
                                              items, catalog, table)
    origin = geometry.choose_origin(items, accepted, anchored=edges)
    warnings += [f"unused: a distance from the diner's edge applies to the origin "
                 f"({origin}), not to {name}" for name in edges if name != origin]
    if origin in edges:
        return origin, edges[origin]
    say(f"asking {llm.model} for the distance of the {origin} from the diner's edge")
    try:
        answer = llm.complete(distances.edge_prompt(origin),
                              options.params.with_seed(seeds.int_seed(seed, "llm.edge", 0)),
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
        warnings.append(f"no distance in {_preview(answer)!r}; used "
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


def _preview(answer: str, limit: int = 120) -> str:
    """An LLM answer shortened for a warning: one line of at most ``limit`` characters."""
    text = " ".join(answer[:4 * limit].split())
    return text if len(text) <= limit else text[:limit - 1] + "…"


def sample_setting(items: Sequence[Item], setting: Setting, table: Table,
                   rng: Callable[[], np.random.Generator], options: ArrangeOptions,
                   region: Polygon | None = None) -> Sampled:
    """The guided layout and M configurations of ``items`` on ``table`` (a diner's place
    box, with its exact ``region``), each measured for fidelity. ``rng`` makes a fresh
    generator: a draw without the gap tolerance starts from the same state."""
    warnings = []
    rels, gaps = setting.relations, setting.gaps
    layout = geometry.guided_layout(items, rels, gaps, table, setting.edge_gap_m, setting.origin)
    tol = options.gap_tolerance_m
    warnings += [f"the other relations keep {r.subject} {r.relation} {r.reference} "
                 f"from its stated {100 * gaps[r.key()]:g} cm"
                 for r in rels if tol is not None and r.key() in gaps
                 and not sampling.realisable(layout, r, gaps[r.key()], items, tol)]
    try:
        configs = sampling.sample_configurations(items, layout, rels, table, rng(),
                                                 m=options.m, gaps_m=gaps, tolerance_m=tol,
                                                 region=region)
    except Infeasible:
        if tol is None:
            raise
        warnings.append(f"no configuration keeps every stated gap within {100 * tol:g} cm; "
                        "sampled without that tolerance")
        configs = sampling.sample_configurations(items, layout, rels, table, rng(),
                                                 m=options.m, gaps_m=gaps, tolerance_m=None,
                                                 region=region)
    measured = tuple(fidelity.measure(c, rels, gaps, layout, table) for c in configs)
    return Sampled(layout, configs, measured, tuple(warnings))


def arrange_items(request: str | Request, items: Sequence[Item], llm: CallLog,
                  catalog: Catalog, table: Table, seed: int = 0,
                  options: ArrangeOptions | None = None,
                  on_event: Callable[[str], None] | None = None) -> ArrangementResult:
    """Arrange ``items`` on ``table``: relations from the LLM, checked, grounded and sampled.

    ``request`` is the request's text, or the :class:`~llm_grop.world.request.Request`
    read from it: then the relations it states join the preferences, and the LLM calls
    and warnings of its reading join the arrangement's.

    Items with a ``diner`` index are several diners' settings (``table.diners`` seats them):
    the LLM is asked once per distinct setting, and each diner's setting is laid out and
    sampled in that diner's place (:mod:`llm_grop.arrangement.diners`).

    Raises :class:`~llm_grop.errors.LLMError` when no attempt yields a usable
    relation and :class:`~llm_grop.errors.Infeasible` when no configuration fits.
    """
    options = options or ArrangeOptions()
    reading_calls: tuple[CallRecord, ...] = ()
    reading_warnings: tuple[str, ...] = ()
    read_by = None
    if isinstance(request, Request):
        read_by = request.source
        options = replace(options, stated=options.stated + request.relations,
                          choices=options.choices + request.choices)
        reading_calls, reading_warnings = request.calls, request.warnings
        request = request.text

    def say(message: str) -> None:
        log.info(message)
        if on_event is not None:
            on_event(message)

    first_call = len(llm.calls)
    if any(it.diner is not None for it in items):
        several = diners.arrange_diners(
            items, table, catalog, seed, say,
            lambda base, box: _symbolic(base, llm, catalog, box, seed, options, say),
            lambda its, st, box, rng, region: sample_setting(its, st, box, rng, options,
                                                             region))
        relations_all = tuple(r for s in several.settings for r in s.relations)
        warnings = tuple(w for s in several.distinct for w in s.warnings) + \
            tuple(w for s in several.sampled for w in s.warnings)
        attempts = tuple(a for s in several.distinct for a in s.attempts)
        dropped = tuple(r for s in several.distinct for r in s.dropped)
        gaps = {k: v for s in several.settings for k, v in s.gaps.items()}
        layout, edge_gap = several.sampled[0].layout, several.settings[0].edge_gap_m
        configs, measured = several.configurations, several.fidelity
    else:
        setting = _symbolic(items, llm, catalog, table, seed, options, say)
        say("sampling configurations")
        one = sample_setting(items, setting, table, lambda: seeds.stream(seed, "sampler"),
                             options)
        relations_all, layout, configs, measured = setting.relations, one.layout, \
            one.configurations, one.fidelity
        warnings = setting.warnings + one.warnings
        attempts, dropped, gaps = setting.attempts, setting.dropped, setting.gaps
        edge_gap = setting.edge_gap_m
    arrangement = Arrangement(
        request=request, table=table, placements=configs[0].placements,
        relations=relations_all,
        llm=LLMSummary(llm.backend, llm.model, reading_calls + tuple(llm.calls[first_call:]),
                       llm.chosen_by),
        warnings=reading_warnings + warnings,
        conflicts=tuple(a.conflict for a in attempts if a.conflict), read_by=read_by,
        origins=tuple((it.name, it.source, it.words) for it in items))
    return ArrangementResult(arrangement, tuple(configs), layout, attempts, dropped, gaps,
                             edge_gap, tuple(measured))
