"""What the executive asks before it gives up an object it still holds, or one a place left
upright on the target table: another spot for it. The executive stays below planning: it
only calls a :class:`Rescue` it is given, and the layer above it (the feedback loop,
:mod:`llm_grop.methods.rescue`) decides."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

from llm_grop.world.arrangement import Placement
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ObjectState, Reason, Step


@dataclass(frozen=True)
class NewSpot:
    """Where to put an object that could not be placed where planned: its new ``target``
    (table frame) and the ``leg`` (a ``navigate`` step: its goal and fallbacks, room
    frame) to the standing position to place it from."""

    target: Placement
    leg: Step


class Rescue(Protocol):
    """Asked by the executive before it gives up ``name`` while the hand still holds it or
    while it stands upright on the target table where a place left it (``slid``,
    ``wrong_support``), for ``reason`` (from the closed list), with every object as
    ``states`` says, the base at ``pose`` and the standing positions already ``tried`` for
    it (room frame). Another spot for it, or ``None``: the executive then gives it up as
    before."""

    def __call__(self, name: str, reason: Reason, states: Mapping[str, ObjectState],
                 pose: Pose2D, tried: Sequence[Pose2D]) -> NewSpot | None: ...
