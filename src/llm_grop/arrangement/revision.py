"""The feedback loop (issue 41): a failure, in words, goes back to the LLM, which revises
its relations; the revision is read by Template 1's reader and checked by clingo.

One :class:`Feedback` serves a whole run: it holds the LLM, the budget of rounds
(``--revisions``, at most N per run) and every round's record
(:class:`~llm_grop.world.failure.Revision`). A revision that reads nothing usable, repeats
the proposal or contradicts itself is refused: the caller keeps the original failure and
the loop says so in one warning.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

from llm_grop import seeds
from llm_grop.arrangement import consistency, relations
from llm_grop.arrangement.answers import read_answer
from llm_grop.errors import ReplayMissing
from llm_grop.llm.base import CallLog, SamplingParams
from llm_grop.llm.embedded import DEFAULT_MODEL as BUNDLED_MODEL
from llm_grop.world.arrangement import Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.failure import Failure, Revision
from llm_grop.world.relation import Relation

#: The sources of relations the LLM stated, which a revision may change.
FROM_LLM = frozenset({"llm", "revision"})

#: Rounds per run when ``--revisions`` is not given, with a model other than the bundled one.
DEFAULT_ROUNDS = 2


def rounds_for(revisions: int | None, model: str) -> int:
    """The rounds a run may spend: ``revisions`` when given; else :data:`DEFAULT_ROUNDS`,
    or 0 when ``model`` is the bundled SmolLM2-135M, live or replayed. Told what failed,
    that small model answered worse than when asked again blindly: on the paper's tasks 5
    and 7 its revisions lowered the rating (``benchmarks/feedback_paper.py``)."""
    if revisions is not None:
        return revisions
    return 0 if model == BUNDLED_MODEL else DEFAULT_ROUNDS


def revision_prompt(items: Sequence[Item], proposed: Sequence[Relation], failure: Failure
                    ) -> str:
    """The revision template (``prompts/revision.txt``) with its slots filled: the objects,
    the proposed relations as Template 1 lines, and the failure's reason."""
    lines = "\n".join(r.sentence() for r in proposed) or "(no relation)"
    return relations.asset("revision.txt").format(
        spatial_relationships=relations.SPATIAL_RELATIONSHIPS,
        objects=relations.object_list([it.name for it in items]),
        proposed=lines, reason=failure.reason).strip()


def logical_failure(conflict: Sequence[Relation]) -> Failure:
    """The failure of relations that contradict each other: clingo's minimal
    ``conflict``, each in the LLM's own words."""
    said = "; ".join(repr(r.line.strip() or r.sentence()) for r in conflict)
    objects = tuple(dict.fromkeys(n for r in conflict for n in (r.subject, r.reference)
                                  if n is not None))
    return Failure("logical", f"these lines contradict each other, so no table can keep "
                              f"them all: {said}", objects, tuple(conflict))


def geometric_failure(objects: Sequence[str], why: str, proposed: Sequence[Relation],
                      where: str) -> Failure:
    """The failure of relations no placement on ``where`` (``"the 0.45 x 0.3 m table"``)
    keeps: the sampler got stuck most at ``objects``, most often because ``why``."""
    involved = tuple(r for r in proposed if r.subject in objects or r.reference in objects)
    names = ", ".join(f"the {n}" for n in objects) or "the objects"
    said = "; ".join(repr(r.sentence()) for r in involved)
    return Failure("geometric", f"{names} cannot be placed where these relations put it on "
                                f"{where}: most places tried were rejected because {why}"
                   + (f" (relations: {said})" if said else ""), tuple(objects), involved)


def reach_failure(name: str, why: str, proposed: Sequence[Relation], where: str) -> Failure:
    """The failure of relations that put ``name`` on ``where`` out of the robot's reach
    in every configuration: ``why`` says how far (the planner's belief)."""
    involved = tuple(r for r in proposed if name in (r.subject, r.reference))
    said = "; ".join(repr(r.sentence()) for r in involved)
    return Failure("physical", f"the robot cannot put the {name} where these relations put "
                               f"it on {where}: {why}"
                   + (f" (relations: {said})" if said else ""), (name,), involved)


#: What each reason the executive gives an object up for means, told to the LLM.
_PHYSICAL = {
    "no_ik": "the arm could not reach that spot from anywhere the robot could stand",
    "blocked": "the robot could not drive to a place beside the table from which to reach "
               "that spot",
    "contact": "the arm bumped into something each time it reached for that spot",
    "slid": "each time it was put there it slid away from the spot",
    "wrong_support": "each time it was put there it came to rest on another object",
}


def physical_failure(name: str, reason: str, x_m: float, y_m: float,
                     proposed: Sequence[Relation], where: str) -> Failure:
    """The failure of a place the robot could not carry out: ``name`` at ``(x_m, y_m)``
    (table frame, metres) on ``where``, given up for ``reason`` (the executive's closed
    list); the other objects are already on the table."""
    involved = tuple(r for r in proposed if name in (r.subject, r.reference))
    why = _PHYSICAL.get(reason, f"each attempt failed ({reason.replace('_', ' ')})")
    said = "; ".join(repr(r.sentence()) for r in involved)
    return Failure("physical", f"the robot could not put the {name} where these relations put "
                               f"it on {where}, {x_m:+.2f} m right and {y_m:+.2f} m away from "
                               f"the table's centre: {why}. The other objects are already on "
                               f"the table and stay where they are"
                   + (f" (relations: {said})" if said else ""), (name,), involved)


@dataclass
class Feedback:
    """The feedback loop's state for one run: the LLM it asks, how it asks, the rounds
    it may still spend and the record of each round. ``rounds`` is the run's budget
    (:func:`rounds_for` of ``--revisions``; 0 turns the loop off: the paper's blind
    re-prompt)."""

    llm: CallLog
    catalog: Catalog
    seed: int
    params: SamplingParams
    rounds: int
    say: Callable[[str], None] = lambda message: None
    done: list[Revision] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    @property
    def left(self) -> int:
        """Rounds still allowed."""
        return self.rounds - len(self.done)

    def revise(self, items: Sequence[Item], proposed: Sequence[Relation], failure: Failure,
               stated: Sequence[Relation] = ()) -> tuple[Relation, ...] | None:
        """One round: tell the LLM ``failure`` of its ``proposed`` relations and read its
        revision. The revised relations (those not in ``proposed`` marked ``revision``),
        or ``None`` when the round is refused (recorded, with one warning), when no round
        is left, or when none of the relations involved (else of those ``proposed``) came
        from the LLM: the user's stand, and the LLM is not asked."""
        if self.left <= 0:
            return None
        if not any(r.source in FROM_LLM for r in failure.relations or proposed):
            return None
        k = len(self.done) + 1
        self.say(f"{failure.kind} failure: {failure.reason}; asking {self.llm.model} to "
                 f"revise its relations (revision {k} of {self.rounds})")
        prompt = revision_prompt(items, proposed, failure)
        try:
            answer = self.llm.complete(
                prompt, replace(self.params, seed=seeds.int_seed(self.seed, "llm.revision", k)),
                relations.template1_grammar(items)).response
        except ReplayMissing:
            return self._refuse(k, failure, prompt, "", proposed, (),
                                "the replayed recording has no answer to it")
        # Read as Template 1's answer is: an object it leaves out gets a follow-up.
        revised = read_answer(answer, items, self.llm, self.catalog, self.params,
                              lambda j: seeds.int_seed(self.seed, "llm.revision", k, j + 1)
                              ).relations
        if not revised:
            return self._refuse(k, failure, prompt, answer, proposed, (),
                                "the answer held no usable relation")
        if {r.key() for r in revised} == {r.key() for r in proposed}:
            return self._refuse(k, failure, prompt, answer, proposed, revised,
                                "the answer repeats the failed relations")
        report = consistency.check([*stated, *revised])
        if not report.consistent:
            return self._refuse(k, failure, prompt, answer, proposed, revised,
                                logical_failure(report.conflict).reason)
        had = {r.key() for r in proposed} | {r.converse().key() for r in proposed
                                              if r.reference is not None}
        marked = tuple(r if r.key() in had else replace(r, source="revision", revision=k)
                       for r in revised)
        done = Revision(k, failure, prompt, answer, tuple(proposed), marked, "accepted")
        self.done.append(done)
        self.say(f"revision {k} accepted: {len(done.added)} relation(s) added, "
                 f"{len(done.removed)} dropped")
        return marked

    def _refuse(self, k: int, failure: Failure, prompt: str, answer: str,
                proposed: Sequence[Relation], revised: Sequence[Relation], why: str) -> None:
        self.done.append(Revision(k, failure, prompt, answer, tuple(proposed), tuple(revised),
                                  "refused", why))
        self.warnings.append(f"revision {k} refused ({why}); kept the {failure.kind} "
                             f"failure: {failure.reason}")
        self.say(f"revision {k} refused: {why}")

