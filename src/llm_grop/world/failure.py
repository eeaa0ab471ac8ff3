"""What went wrong with an arrangement, in words an LLM can act on, and what the feedback
loop asked and got back (issue 41): one record for the three kinds of failure."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from llm_grop.world.relation import Relation

FailureKind = Literal["logical", "geometric", "physical"]
#: The kinds of failure: relations that contradict each other (clingo), relations no
#: placement on the table keeps (the sampler), and a plan the robot could not carry out
#: (the executive).
FAILURE_KINDS: tuple[FailureKind, ...] = ("logical", "geometric", "physical")

RevisionOutcome = Literal["accepted", "refused"]


@dataclass(frozen=True)
class Failure:
    """Why an arrangement's relations could not be realised.

    ``kind`` is one of :data:`FAILURE_KINDS`; ``objects`` the objects involved (names);
    ``relations`` the relations involved (for ``logical``, clingo's minimal conflict);
    ``reason`` the failure in plain words, as the LLM is told it.
    """

    kind: FailureKind
    reason: str
    objects: tuple[str, ...] = ()
    relations: tuple[Relation, ...] = ()

    def __post_init__(self) -> None:
        if self.kind not in FAILURE_KINDS:
            raise ValueError(f"unknown failure kind {self.kind!r}")


@dataclass(frozen=True)
class Revision:
    """One round of the feedback loop: the failure, the prompt that told the LLM about
    it, the LLM's answer, and what came of it.

    ``proposed`` are the relations that failed; ``revised`` the relations read from the
    answer (empty when nothing usable was read); ``outcome`` ``accepted`` when the
    revised relations replaced the proposed ones, else ``refused`` with ``note`` saying
    why (the answer held no relation, repeated the proposal, or contradicted itself).
    """

    round: int
    failure: Failure
    asked: str
    answer: str
    proposed: tuple[Relation, ...]
    revised: tuple[Relation, ...]
    outcome: RevisionOutcome
    note: str = ""

    @property
    def added(self) -> tuple[Relation, ...]:
        """Revised relations the proposal did not state (either way round)."""
        had = _keys(self.proposed)
        return tuple(r for r in self.revised if r.key() not in had)

    @property
    def removed(self) -> tuple[Relation, ...]:
        """Proposed relations the revision no longer states (either way round)."""
        kept = _keys(self.revised)
        return tuple(r for r in self.proposed if r.key() not in kept)


def _keys(relations: tuple[Relation, ...]) -> set[tuple[str, str, str | None]]:
    """Each relation's key and its converse's."""
    out = {r.key() for r in relations}
    out |= {r.converse().key() for r in relations if r.reference is not None}
    return out
