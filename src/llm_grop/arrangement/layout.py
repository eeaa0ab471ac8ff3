"""The guided layout (positions, the sampler's spreads and sampling order) and the spreads
it is made with, in metres; :mod:`llm_grop.arrangement.geometry` computes it."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from llm_grop.world.relation import (
    ABOVE,
    ABOVE_LEFT,
    ABOVE_RIGHT,
    BELOW,
    BELOW_LEFT,
    BELOW_RIGHT,
    LEFT,
    RIGHT,
)

#: Sampling std dev, metres, along an axis on which a gap was stated: a third of the
#: fidelity tolerance, so that nearly every draw keeps the gap.
GAP_SIGMA_M = 0.005

#: Sampling std dev, metres, across a cardinal relation's direction (the authors' value).
ACROSS_SIGMA_M = 0.01

#: Sampling std dev ``(sx, sy)`` in metres, relative to the anchor, by the relation that
#: placed an object: tight along the gap, looser across a cardinal relation's direction.
SIGMA_BY_RELATION_M: Mapping[str, tuple[float, float]] = {
    ABOVE: (ACROSS_SIGMA_M, GAP_SIGMA_M), BELOW: (ACROSS_SIGMA_M, GAP_SIGMA_M),
    LEFT: (GAP_SIGMA_M, ACROSS_SIGMA_M), RIGHT: (GAP_SIGMA_M, ACROSS_SIGMA_M),
    ABOVE_LEFT: (GAP_SIGMA_M, GAP_SIGMA_M), ABOVE_RIGHT: (GAP_SIGMA_M, GAP_SIGMA_M),
    BELOW_LEFT: (GAP_SIGMA_M, GAP_SIGMA_M), BELOW_RIGHT: (GAP_SIGMA_M, GAP_SIGMA_M),
}

#: Std dev in metres for an origin with no stated distance from the diner, or an
#: unconnected group's origin (the authors' value).
FREE_SIGMA_M = (0.03, 0.03)

#: Std dev in metres for the origin placed at the diner's stated distance: free along
#: the edge (where the whole setting sits), tight towards the diner.
DINER_SIGMA_M = (FREE_SIGMA_M[0], GAP_SIGMA_M)

#: Std dev in metres for an object resting on another: it follows its support's
#: sampled position almost exactly. (An object placed as the support *under* a
#: placed one takes that object's std dev instead: it carries the stack.)
STACK_SIGMA_M = (0.002, 0.002)

Key = tuple[str, str, str | None]


@dataclass(frozen=True)
class GuidedLayout:
    """LLM-guided positions and the sampler's settings, in the table frame, in metres.

    ``positions``: guided centre ``(x, y)`` per item. ``sigma``: Gaussian std dev
    ``(sx, sy)`` per item. ``support``: what each item rests on (``None``: the table).
    ``order``: the sampling order, the origin first, then breadth-first along the
    relations; a support always comes before what it supports. ``anchor``: the object,
    earlier in ``order``, whose sampled position each item is drawn around (``None``: an
    origin, drawn around its own position). ``edge_gap_m``: the origin's stated distance
    from the diner's edge of the table (``None``: not stated; the origin is at the centre).
    """

    origin: str
    positions: Mapping[str, tuple[float, float]]
    sigma: Mapping[str, tuple[float, float]]
    support: Mapping[str, str | None]
    order: tuple[str, ...]
    anchor: Mapping[str, str | None] = field(default_factory=dict)
    edge_gap_m: float | None = None

    def offset(self, name: str) -> tuple[float, float]:
        """``name``'s guided position relative to its anchor's (its own if it has none)."""
        x, y = self.positions[name]
        a = self.anchor.get(name)
        if a is None:
            return (x, y)
        ax, ay = self.positions[a]
        return (x - ax, y - ay)
