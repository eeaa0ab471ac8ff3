"""The semantic arrangement pipeline (paper §III-A and §III-B).

request items -> Template 1 -> parsed relations (+ follow-ups for left-out objects)
-> clingo consistency check (re-prompt with a new seed on conflict, bounded)
-> Template 2 distances -> LLM-guided positions -> M sampled configurations.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

from llm_grop import seeds
from llm_grop.arrangement import (
    consistency,
    distances,
    geometry,
    preferences,
    relations,
    sampling,
)
from llm_grop.errors import LLMError
from llm_grop.llm.base import CallLog, SamplingParams
from llm_grop.world.arrangement import Arrangement, Configuration, Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.llmlog import LLMSummary
from llm_grop.world.relation import CENTER, STACKING, Relation
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
    the answer.
    """

    m: int = 25
    max_attempts: int = 3
    examples: str | None = None
    notes: str = ""
    params: SamplingParams = field(default_factory=SamplingParams)
    reprompt_temperature_step: float = 0.3
    preferences: tuple[str, ...] = ()
    preference_pool: tuple[str, ...] = ()


@dataclass(frozen=True)
class Attempt:
    """One Template 1 answer: what was read from it and what clingo said."""

    seed: int
    relations: tuple[Relation, ...]
    conflict: tuple[Relation, ...]
    ignored: tuple[str, ...]

    @property
    def consistent(self) -> bool:
        """Usable as it is: at least one relation and no conflict."""
        return bool(self.relations) and not self.conflict


@dataclass(frozen=True)
class ArrangementResult:
    """Everything :func:`arrange_items` found.

    ``arrangement`` holds the first configuration; ``configurations`` all M of
    them (the planner chooses among these); ``dropped`` the LLM lines left out
    to restore consistency.
    """

    arrangement: Arrangement
    configurations: tuple[Configuration, ...]
    layout: geometry.GuidedLayout
    attempts: tuple[Attempt, ...]
    dropped: tuple[Relation, ...]
    gaps_m: dict[tuple[str, str, str | None], float]


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
    parsed = relations.parse_relations(record.response, items, catalog)
    found = list(parsed.relations)
    ignored = list(parsed.ignored)
    if len(items) > 1:
        for k, missing in enumerate(parsed.missing):
            anchor = _anchor_for(missing, items, found)
            record = llm.complete(
                relations.followup_prompt(missing, anchor),
                options.params.with_seed(seeds.int_seed(seed, "llm.followup", attempt, k)),
                relations.followup_grammar(missing, anchor))
            answer = relations.parse_relations(record.response, items, catalog)
            found += [r for r in answer.relations if missing in (r.subject, r.reference)]
            ignored += list(answer.ignored)
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


def arrange_items(request: str, items: Sequence[Item], llm: CallLog, catalog: Catalog,
                  table: Table, seed: int = 0, options: ArrangeOptions | None = None,
                  on_event: Callable[[str], None] | None = None) -> ArrangementResult:
    """Arrange ``items`` on ``table``: relations from the LLM, checked, grounded and sampled.

    Raises :class:`~llm_grop.errors.LLMError` when no attempt yields a usable
    relation and :class:`~llm_grop.errors.Infeasible` when no configuration fits.
    """
    options = options or ArrangeOptions()
    def say(message: str) -> None:
        log.info(message)
        if on_event is not None:
            on_event(message)

    first_call = len(llm.calls)
    warnings: list[str] = []
    attempts: list[Attempt] = []
    accepted: tuple[Relation, ...] = ()
    dropped: list[Relation] = []
    prefs = preferences.read_preferences(options.preferences, options.preference_pool,
                                         items, catalog)
    if preferences.covers(prefs, items):
        say("the preferences relate every object: Template 1 is not asked")
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
                raise LLMError(
                    f"{llm.backend} LLM gave no usable spatial relation in "
                    f"{options.max_attempts} attempt(s){detail}")
            warnings += [f"dropped to restore consistency: {r.line or r.sentence()}"
                         for r in dropped]
        for attempt in attempts:
            warnings += [f"ignored LLM line: {line}" for line in attempt.ignored if line]
    if prefs:
        accepted, overridden = preferences.merge(prefs, accepted)
        warnings += [f"overridden by a preference: {r.line or r.sentence()}"
                     for r in overridden]

    gaps: dict[tuple[str, str, str | None], float] = {}
    stated = preferences.stated_gaps(prefs, table)
    for k, rel in enumerate(accepted):
        if rel.relation == CENTER or rel.relation in STACKING:
            continue
        if rel.key() in stated:
            gaps[rel.key()] = stated[rel.key()]
            continue
        say(f"asking {llm.model} for the distance: {rel.sentence()}")
        record = llm.complete(distances.template2_prompt(rel),
                              options.params.with_seed(seeds.int_seed(seed, "llm.distance", k)),
                              distances.template2_grammar())
        gaps[rel.key()], defaulted = distances.parse_distance_m(record.response)
        if defaulted:
            warnings.append(f"no distance in {record.response.strip()!r}; used "
                            f"{distances.DEFAULT_GAP_CM:g} cm for: {rel.sentence()}")

    say("sampling configurations")
    layout = geometry.guided_layout(items, accepted, gaps, table)
    configs = sampling.sample_configurations(items, layout, accepted, table,
                                             seeds.stream(seed, "sampler"), m=options.m)
    arrangement = Arrangement(
        request=request, table=table, placements=configs[0].placements, relations=accepted,
        llm=LLMSummary(llm.backend, llm.model, tuple(llm.calls[first_call:])),
        warnings=tuple(warnings),
        conflicts=tuple(a.conflict for a in attempts if a.conflict))
    return ArrangementResult(arrangement, configs, layout, tuple(attempts), tuple(dropped), gaps)
