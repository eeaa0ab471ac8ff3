"""Generalising a learned style to objects the examples do not show (issue 42, the way
TidyBot summarises a person's placements into rules).

The LLM is given the sentences learned exactly from the examples (:mod:`.learning`) and
the catalog's other objects, and asked where the same person would put each of them, one
``Place ...`` line per object (the template ``prompts/generalise.txt``). Each line is read
by Template 1's reader over the catalog's objects (the one vocabulary). A rule is kept
when

* it places an object the examples do not show (the examples' own objects are theirs: the
  exact sentences always win),
* relative to an object the examples show, or one a rule kept before placed, so the
  learned sentences stay a tree rooted at the setting's main object (:mod:`.learning`),
* it is the first rule for that object, and
* clingo finds it consistent with the exact sentences and the rules kept before it.

A rule that sets an object beside another takes the style's spacing: the median of the
exact sentences' gaps (a person who leaves 8 cm between plate and fork leaves it between
the forks too); a stacking rule has none, nor does any rule when the examples show no
gap. What is not kept is said in one warning. Without a capable model the exact
sentences alone are learned, with one warning (the caller's: :func:`llm_grop.api.learn`).
"""

from __future__ import annotations

import statistics
from collections.abc import Sequence
from dataclasses import replace

from llm_grop import seeds
from llm_grop.arrangement import consistency, relations
from llm_grop.arrangement.learning import Learned, Learning
from llm_grop.arrangement.phrasing import phrase, round_cm
from llm_grop.language.answer_reader import parse_relations
from llm_grop.llm.base import CallLog, SamplingParams
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import STACKING, Relation
from llm_grop.world.request import items_from_names


def generalise_prompt(exact: Sequence[Learned], others: Sequence[str]) -> str:
    """The template with the exact sentences and the ``others`` (catalog objects the
    examples do not show) in its slots."""
    return relations.asset("generalise.txt").format(
        spatial_relationships=relations.SPATIAL_RELATIONSHIPS,
        sentences="\n".join(f"- {s.sentence}" for s in exact),
        others=relations.object_list(list(others))).strip()


def generalise(learning: Learning, llm: CallLog, catalog: Catalog, seed: int = 0,
               params: SamplingParams | None = None) -> Learning:
    """``learning`` with the LLM's rules for the catalog's objects its examples do not
    show (the module doc), each a :class:`~.learning.Learned` with the style's spacing (no
    spread) whose source names the model; one warning for the rules not kept."""
    pairs = [s for s in learning.sentences if s.reference is not None]
    if not pairs:
        return learning
    seen = {n for s in pairs for n in (s.subject, s.reference) if n is not None}
    others = [n for n in catalog.names() if n not in seen]
    if not others:
        return learning
    asked = replace(params or SamplingParams(), seed=seeds.int_seed(seed, "llm.generalise"))
    answer = llm.complete(generalise_prompt(pairs, others), asked).response
    everything = items_from_names(catalog.names(), catalog)
    said = parse_relations(answer, everything, catalog).relations
    exact = [Relation(s.subject, s.relation, s.reference, source="learned")
             for s in pairs if s.relation is not None]
    gaps = [s.gap_cm for s in pairs if s.gap_cm is not None]
    spacing_cm = round_cm(statistics.median(gaps)) if gaps else None
    placed, kept, left = set(seen), [], []
    for rule in said:
        why = _refusal(rule, seen, placed, [*exact, *(r for r, _ in kept)])
        if why is not None:
            left.append(f"'{rule.sentence()}' ({why})")
            continue
        gap_cm = None if rule.relation in STACKING else spacing_cm
        sentence = phrase(rule.subject, rule.relation, rule.reference, gap_cm, everything,
                          catalog)
        if sentence is None:
            left.append(f"'{rule.sentence()}' (does not read back as a preference)")
            continue
        placed.add(rule.subject)
        kept.append((rule, Learned(sentence, rule.subject, rule.relation, rule.reference,
                                   gap_cm, None, (f"a rule by {llm.model}",))))
    warnings = list(learning.warnings)
    if left:
        warnings.append(f"{len(left)} of the {llm.model}'s rules not learned: "
                        + "; ".join(left))
    if not said:
        warnings.append(f"{llm.model} gave no rule that reads as a relation between "
                        "catalog objects; only the exact sentences are learned")
    return replace(learning, sentences=learning.sentences + tuple(x for _, x in kept),
                   warnings=tuple(warnings))


def _refusal(rule: Relation, seen: set[str], placed: set[str],
             held: Sequence[Relation]) -> str | None:
    """Why ``rule`` is not kept, or ``None`` (the module doc's conditions)."""
    if rule.reference is None:
        return "it relates the object to no other"
    if rule.subject in seen:
        return "the examples show where it goes"
    if rule.subject in placed:
        return "a rule before it places that object"
    if rule.reference not in placed:
        return "it relates the object to one neither the examples nor a rule places"
    if consistency.check([*held, rule]).conflict:
        return "clingo finds it contradicts what was learned"
    return None

