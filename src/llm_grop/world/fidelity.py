"""How far a configuration realises what was said about it: stated gaps against realised
ones, and how far the setting's origin moved from where the diner's distance put it.
Representation only; :mod:`llm_grop.arrangement.fidelity` measures it. Lengths in metres.
"""

from __future__ import annotations

from dataclasses import dataclass

#: A stated gap (or distance from the diner) is kept when a configuration realises it
#: within this many metres either way: what the sampler allows and what the planner may
#: give up when it moves a setting within the arm's reach.
GAP_TOLERANCE_M = 0.015


@dataclass(frozen=True)
class GapFidelity:
    """One relation's gap: ``stated_m`` (from the LLM or a preference) and ``realised_m``
    in the configuration, both between edges, metres (see
    :func:`llm_grop.arrangement.fidelity.realised_gap_m`)."""

    subject: str
    relation: str
    reference: str
    stated_m: float
    realised_m: float

    @property
    def error_m(self) -> float:
        """Realised minus stated, metres."""
        return self.realised_m - self.stated_m


@dataclass(frozen=True)
class Fidelity:
    """How faithfully one configuration realises the arrangement's stated geometry.

    ``gaps``: every relation with a stated gap. ``origin``: the layout's origin object;
    ``origin_shift_m``: how far its centre lies from its guided position, metres.
    ``edge_stated_m`` / ``edge_realised_m``: the origin's distance from the diner's edge
    of the table, stated and realised (``None`` when no distance was stated).
    """

    gaps: tuple[GapFidelity, ...] = ()
    origin: str = ""
    origin_shift_m: float = 0.0
    edge_stated_m: float | None = None
    edge_realised_m: float | None = None

    @property
    def max_gap_error_m(self) -> float:
        """The largest ``|realised - stated|`` over the gaps and the diner's distance, metres."""
        errors = [abs(g.error_m) for g in self.gaps]
        if self.edge_stated_m is not None and self.edge_realised_m is not None:
            errors.append(abs(self.edge_realised_m - self.edge_stated_m))
        return max(errors, default=0.0)

    @property
    def infidelity_m(self) -> float:
        """What GROP's utility charges for: the sum of ``|realised - stated|`` over the gaps
        plus the origin's shift, metres."""
        return sum(abs(g.error_m) for g in self.gaps) + self.origin_shift_m


@dataclass(frozen=True)
class Considered:
    """One configuration as GROP scored it: ``utility`` (seconds, ``None`` when it has no
    plan), ``feasibility``, ``cost_s``, its ``fidelity``, and ``score``, the utility minus
    the fidelity penalty, which GROP maximises (``None`` without a plan)."""

    index: int
    utility: float | None
    feasibility: float | None
    cost_s: float | None
    fidelity: Fidelity
    score: float | None
