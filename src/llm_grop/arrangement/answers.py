"""Reading a Template 1-style answer (Template 1's, or a revision's): its relations, and a
follow-up question for each object it leaves out (paper §III-A)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from llm_grop.arrangement import relations
from llm_grop.language.answer_reader import parse_relations
from llm_grop.llm.base import CallLog, SamplingParams
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.relation import CENTER, Relation, dedupe


@dataclass(frozen=True)
class Read:
    """What an answer and its follow-ups said: the relations, without repeats, and the
    lines that could not be used (an ambiguous line, "beside", is one of them)."""

    relations: tuple[Relation, ...]
    ignored: tuple[str, ...]


def anchor_for(missing: str, items: Sequence[Item], rels: Sequence[Relation]) -> str:
    """The object a follow-up asks about: the centre object, else the largest other item."""
    for r in rels:
        if r.relation == CENTER and r.subject != missing:
            return r.subject
    others = [it for it in items if it.name != missing]
    return max(others, key=lambda it: it.spec.area).name


def read_answer(answer: str, items: Sequence[Item], llm: CallLog, catalog: Catalog,
                params: SamplingParams, followup_seed: Callable[[int], int]) -> Read:
    """The relations ``answer`` states between ``items``, with a follow-up question (seeded
    ``followup_seed(k)`` for the ``k``-th) for each object it leaves out."""
    parsed = parse_relations(answer, items, catalog)
    found = list(parsed.relations)
    # Template 1 asks for one relation per pair; an ambiguous line ("beside") is none.
    ignored = list(parsed.ignored) + [c.words for c in parsed.choices]
    if len(items) > 1:
        for k, missing in enumerate(parsed.missing):
            anchor = anchor_for(missing, items, found)
            record = llm.complete(relations.followup_prompt(missing, anchor),
                                  params.with_seed(followup_seed(k)),
                                  relations.followup_grammar(missing, anchor))
            more = parse_relations(record.response, items, catalog)
            found += [r for r in more.relations if missing in (r.subject, r.reference)]
            ignored += list(more.ignored) + [c.words for c in more.choices]
    return Read(dedupe(found), tuple(ignored))
