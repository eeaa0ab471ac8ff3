"""The semantic arrangement pipeline (paper §III-A and §III-B).

request items -> Template 1 -> parsed relations (+ follow-ups for left-out objects)
-> clingo consistency check (on conflict the LLM is told what clashed and revises its
   answer, :mod:`~llm_grop.arrangement.revision`; then, or with ``--revisions 0``, it is
   asked again with a new seed, bounded)
-> Template 2 distances, and the origin object's distance from the diner's edge
-> LLM-guided positions -> M sampled configurations, each measured for fidelity (when none
   keeps the relations, the LLM is told which object did not fit and revises them).
"""

from __future__ import annotations

import logging
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from shapely.geometry import Polygon

from llm_grop import seeds
from llm_grop.arrangement import (
    consistency,
    diners,
    fidelity,
    geometry,
    preferences,
    relations,
    revision,
    sampling,
)
from llm_grop.arrangement.answers import read_answer
from llm_grop.arrangement.grounding import Grounding, ground, preview, stated_for
from llm_grop.arrangement.layout import GuidedLayout
from llm_grop.arrangement.options import ArrangeOptions, Reach
from llm_grop.arrangement.revision import Feedback, rounds_for
from llm_grop.arrangement.setting import Attempt, Sampled, Setting
from llm_grop.errors import Infeasible, LLMAnswerUnusable, NoArrangement, OutOfReach
from llm_grop.llm.base import CallLog
from llm_grop.world.arrangement import Arrangement, Configuration, Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.failure import Revision
from llm_grop.world.fidelity import Fidelity
from llm_grop.world.llmlog import CallRecord, LLMSummary
from llm_grop.world.relation import Relation
from llm_grop.world.request import Request
from llm_grop.world.table import Table

__all__ = ["ArrangeOptions", "ArrangementResult", "arrange_items", "sample_revising",
           "sample_setting"]

log = logging.getLogger(__name__)


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

    @property
    def revisions(self) -> tuple[Revision, ...]:
        """The feedback loop's rounds (the arrangement's)."""
        return self.arrangement.revisions


def _ask_relations(items: Sequence[Item], llm: CallLog, catalog: Catalog, seed: int,
                   attempt: int, options: ArrangeOptions) -> Attempt:
    kwargs = {} if options.examples is None else {"examples": options.examples}
    prompt = relations.template1_prompt(items, notes=options.notes, **kwargs)
    s = seeds.int_seed(seed, "llm.relations", attempt)
    temperature = min(1.0, options.params.temperature + attempt * options.reprompt_temperature_step)
    params = replace(options.params, seed=s, temperature=max(temperature,
                                                               options.params.temperature))
    record = llm.complete(prompt, params, relations.template1_grammar(items))
    read = read_answer(record.response, items, llm, catalog, options.params,
                       lambda k: seeds.int_seed(seed, "llm.followup", attempt, k))
    report = consistency.check(read.relations)
    return Attempt(s, read.relations, report.conflict, read.ignored)


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


def _symbolic(items: Sequence[Item], table: Table, g: Grounding, feedback: Feedback
              ) -> Setting:
    """Relations (Template 1, preferences, clingo; a contradiction explained back to the
    LLM while ``feedback`` has rounds left), gaps (Template 2) and the diner's distance for
    one setting of ``items`` on a place of ``table``'s size."""
    llm, options = g.llm, g.options
    warnings: list[str] = []
    attempts: list[Attempt] = []
    accepted: tuple[Relation, ...] = ()
    dropped: list[Relation] = []
    stated = stated_for(items, options, g.catalog)
    if preferences.covers(stated.relations, items):
        g.say("the stated relations relate every object: Template 1 is not asked")
    elif len(items) > 1:
        for k in range(options.max_attempts):
            g.say(f"asking {llm.model} for symbolic relations "
                  f"(attempt {k + 1}/{options.max_attempts})")
            attempt = _ask_relations(items, llm, g.catalog, g.seed, k, options)
            attempts.append(attempt)
            if attempt.conflict:
                log.info("attempt %d conflicts: %s", k + 1,
                         "; ".join(r.line or r.sentence() for r in attempt.conflict))
            if attempt.consistent:
                accepted = attempt.relations
                break
            revised = _revise_conflict(items, attempt, feedback)
            if revised is not None:
                accepted = revised
                break
        else:
            accepted, dropped = _choose_relations(attempts)
            if not accepted:
                last = attempts[-1] if attempts else None
                detail = f"; last answer had {len(last.relations)} relation(s)" if last else ""
                raise LLMAnswerUnusable(
                    f"{llm.backend} LLM gave no usable spatial relation in "
                    f"{options.max_attempts} attempt(s){detail}")
            warnings += [f"dropped to restore consistency: {preview(r.line or r.sentence())}"
                         for r in dropped]
        for attempt in attempts:
            warnings += [f"ignored LLM line: {line}" for line in attempt.ignored if line]
    return ground(items, accepted, stated, table, g, attempts=attempts, dropped=dropped,
                  warnings=warnings)


def _revise_conflict(items: Sequence[Item], attempt: Attempt, feedback: Feedback
                     ) -> tuple[Relation, ...] | None:
    """The LLM's revision of ``attempt``'s contradicting relations, told what clashed; a
    revision that clashes again is explained in turn while rounds are left. ``None`` when
    no round is left or a revision is refused for another reason."""
    proposed, conflict = attempt.relations, attempt.conflict
    while conflict and feedback.left > 0:
        revised = feedback.revise(items, proposed, revision.logical_failure(conflict))
        if revised is not None:
            return revised
        again = feedback.done[-1].revised
        if not again or {r.key() for r in again} == {r.key() for r in proposed}:
            return None
        proposed, conflict = again, consistency.check(again).conflict
    return None


def _revise_geometry(items: Sequence[Item], setting: Setting, table: Table,
                     failure: NoArrangement, g: Grounding, feedback: Feedback
                     ) -> Setting | None:
    """``setting`` with the LLM's revision of its relations, told which object no
    placement on ``table`` could hold and why; ``None`` when no round is left or the
    revision is refused."""
    if feedback.left <= 0:
        return None
    where = f"the {table.label}"
    told = revision.reach_failure(failure.objects[0], failure.why, setting.relations, where) \
        if isinstance(failure, OutOfReach) else \
        revision.geometric_failure(failure.objects, failure.why, setting.relations, where)
    revised = feedback.revise(items, setting.relations, told)
    if revised is None:
        return None
    return ground(items, revised, stated_for(items, g.options, g.catalog), table, g,
                  attempts=setting.attempts, dropped=setting.dropped,
                  warnings=setting.warnings, known=setting)


def sample_revising(items: Sequence[Item], setting: Setting, table: Table,
                    rng: Callable[[], np.random.Generator], options: ArrangeOptions,
                    revise: Callable[[Setting, NoArrangement], Setting | None],
                    region: Polygon | None = None) -> tuple[Sampled, Setting]:
    """:func:`sample_setting`, and when no configuration keeps the relations, or every
    one puts an object out of the robot's reach (``options.reach``), sampled again with
    ``revise``'s revision of them while it gives one; the sampled setting and the setting
    it kept. Raises the sampler's :class:`~llm_grop.errors.Infeasible` when ``revise``
    gives none (out of reach, the sampling stands: planning says why)."""
    while True:
        try:
            sampled = sample_setting(items, setting, table, rng, options, region)
        except NoArrangement as exc:
            revised = revise(setting, exc)
            if revised is None:
                raise
            setting = revised
            continue
        out = _out_of_reach(sampled.configurations, options.reach)
        revised = None if out is None else revise(setting, out)
        if revised is None:
            return sampled, setting
        setting = revised


def _out_of_reach(configs: Sequence[Configuration], reach: Reach | None) -> OutOfReach | None:
    """The failure of ``configs`` when every one puts an object out of ``reach``: the
    object most of them do, and why; ``None`` when one keeps every object in reach."""
    if reach is None:
        return None
    out = [reach(c.placements) for c in configs]
    if not out or any(o is None for o in out):
        return None
    (name, why), _ = Counter(o for o in out if o is not None).most_common(1)[0]
    return OutOfReach(f"{name} is out of the robot's reach in every configuration ({why})",
                      (name,), why)


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

    A contradiction among the LLM's relations, and relations no configuration keeps, are
    explained back to the LLM for a revision (at most ``options.revisions`` rounds, all
    recorded in ``revisions``; :mod:`llm_grop.arrangement.revision`).

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
    g = Grounding(llm, catalog, seed, options, say)
    feedback = Feedback(llm, catalog, seed, options.params,
                        rounds_for(options.revisions, llm.model), say)

    def revise(its: Sequence[Item], st: Setting, box: Table, exc: NoArrangement
               ) -> Setting | None:
        return _revise_geometry(its, st, box, exc, g, feedback)

    if any(it.diner is not None for it in items):
        several = diners.arrange_diners(
            items, table, catalog, seed, say,
            lambda base, box: _symbolic(base, box, g, feedback),
            lambda its, st, box, rng, region: sample_setting(its, st, box, rng, options,
                                                             region), revise,
            None if options.reach is None else
            lambda configs: _out_of_reach(configs, options.reach))
        relations_all = tuple(r for s in several.settings for r in s.relations)
        warnings = tuple(w for s in several.distinct for w in s.warnings) + \
            tuple(w for s in several.sampled for w in s.warnings)
        attempts = tuple(a for s in several.distinct for a in s.attempts)
        dropped = tuple(r for s in several.distinct for r in s.dropped)
        gaps = {k: v for s in several.settings for k, v in s.gaps.items()}
        layout, edge_gap = several.sampled[0].layout, several.settings[0].edge_gap_m
        configs, measured = several.configurations, several.fidelity
    else:
        setting = _symbolic(items, table, g, feedback)
        say("sampling configurations")
        one, setting = sample_revising(
            items, setting, table, lambda: seeds.stream(seed, "sampler"), options,
            lambda st, exc: revise(items, st, table, exc))
        relations_all, layout, configs, measured = setting.relations, one.layout, \
            one.configurations, one.fidelity
        warnings = setting.warnings + one.warnings
        attempts, dropped, gaps = setting.attempts, setting.dropped, setting.gaps
        edge_gap = setting.edge_gap_m
    warnings += tuple(feedback.warnings) + options.learned_warnings
    arrangement = Arrangement(
        request=request, table=table, placements=configs[0].placements,
        relations=relations_all,
        llm=LLMSummary(llm.backend, llm.model, reading_calls + tuple(llm.calls[first_call:]),
                       llm.chosen_by),
        warnings=reading_warnings + warnings,
        conflicts=tuple(a.conflict for a in attempts if a.conflict), read_by=read_by,
        origins=tuple((it.name, it.source, it.words) for it in items),
        revisions=tuple(feedback.done))
    return ArrangementResult(arrangement, tuple(configs), layout, attempts, dropped, gaps,
                             edge_gap, tuple(measured))
