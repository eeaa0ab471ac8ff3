"""The arrangement pipeline's options (:func:`llm_grop.arrangement.pipeline.arrange_items`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

from llm_grop.arrangement import fidelity
from llm_grop.llm.base import SamplingParams
from llm_grop.settings import DEFAULTS
from llm_grop.world.arrangement import Placement
from llm_grop.world.relation import Choice, Relation


class Reach(Protocol):
    """The planner's view of what the robot can reach, given to the arrangement from above
    (:mod:`llm_grop.methods.reach`): for a configuration's ``placements`` (table frame),
    the first object it believes cannot be placed from anywhere the robot can stand, with
    why in words, or ``None`` when every one can."""

    def __call__(self, placements: Sequence[Placement]) -> tuple[str, str] | None: ...


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
    ``revisions``: rounds of the feedback loop (:mod:`llm_grop.arrangement.revision`) per
    run; 0 re-prompts blindly on a contradiction, as the paper does; ``None``: as
    :func:`~llm_grop.arrangement.revision.rounds_for` says for the run's model.
    ``reach``: when given, a sampling whose every configuration puts an object out of the
    robot's reach is a failure told to the LLM, while rounds are left (with several
    diners, of the setting whose object it is, checked on the whole table's
    configurations); ``None``: planning finds it.
    ``learned``: sentences learned from example settings (``--examples``;
    :mod:`llm_grop.arrangement.learning`), each with the settings it was read off; they
    apply as ``preference_pool``'s do, as relations of source ``learned``.
    ``learned_warnings``: what learning them warned of, added to the arrangement's
    warnings.
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
    revisions: int | None = DEFAULTS.revisions
    reach: Reach | None = None
    learned: tuple[tuple[str, tuple[str, ...]], ...] = ()
    learned_warnings: tuple[str, ...] = ()
