"""The phrasing corpus (``phrasings.yaml``) as readings: shared by the corpus tests and by
``benchmarks/phrasings.py``."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import yaml

from llm_grop.language.reading import Reading, ReadObject, ReadRelation

CORPUS = Path(__file__).with_name("phrasings.yaml")


@dataclass(frozen=True)
class Case:
    """One phrasing: its text, the reading a person means, whether the catalog matcher reads
    it alone (``fast``), and its tags."""

    text: str
    expected: Reading
    fast: bool
    tags: tuple[str, ...]


def expected_reading(case: dict[str, Any]) -> Reading:
    """The reading a corpus entry gives: objects it lists under ``guessed`` come from the
    LLM, the others from the request."""
    guessed = set(case.get("guessed", ()))
    objects = tuple(ReadObject(n, k, "llm" if n in guessed else "request")
                    for n, k in case["objects"])
    relations = []
    for r in case.get("relations", ()):
        r = [*r, None, None][:5]
        relations.append(ReadRelation(r[0], r[1], r[2], r[3], r[4]))
    return Reading(" ".join(case["text"].split()), objects, tuple(relations),
                   case.get("diners", 1), "llm")


def load_cases() -> list[Case]:
    """Every phrasing of the corpus."""
    data = yaml.safe_load(CORPUS.read_text(encoding="utf-8"))
    return [Case(c["text"], expected_reading(c), bool(c.get("fast")), tuple(c.get("tags", ())))
            for c in data["phrasings"]]


def load_refusals() -> list[tuple[str, str]]:
    """``(text, reason)`` of every request the corpus says must be refused."""
    data = yaml.safe_load(CORPUS.read_text(encoding="utf-8"))
    return [(c["text"], c["reason"]) for c in data["refusals"]]


def as_answer(reading: Reading) -> Reading:
    """``reading`` as a model that reads well would answer it: every part quoting the
    request's words."""
    return replace(reading, relations=tuple(replace(r, words=reading.text)
                                            for r in reading.relations))


def same(got: Reading, want: Reading) -> bool:
    """Whether two readings mean the same (who read it and the words aside)."""
    return got.meaning() == want.meaning()
