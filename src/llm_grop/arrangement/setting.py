"""What the arrangement pipeline knows about one setting, before and after sampling."""

from __future__ import annotations

from dataclasses import dataclass

from llm_grop.arrangement.layout import GuidedLayout
from llm_grop.world.arrangement import Configuration
from llm_grop.world.fidelity import Fidelity
from llm_grop.world.relation import Relation


@dataclass(frozen=True)
class Attempt:
    """One Template 1 answer: what was read from it and what clingo said."""

    seed: int
    relations: tuple[Relation, ...]
    conflict: tuple[Relation, ...]
    ignored: tuple[str, ...]

    @property
    def consistent(self) -> bool:
        """Usable as it is: at least one relation and no conflict."""
        return bool(self.relations) and not self.conflict


@dataclass(frozen=True)
class Setting:
    """What the LLM and the preferences say about one setting: its relations, gaps, origin
    and the origin's distance from the diner's edge (metres)."""

    relations: tuple[Relation, ...]
    gaps: dict[tuple[str, str, str | None], float]
    origin: str
    edge_gap_m: float
    attempts: tuple[Attempt, ...]
    dropped: tuple[Relation, ...]
    warnings: tuple[str, ...]


@dataclass(frozen=True)
class Sampled:
    """One diner's setting, sampled in its place frame: the layout, the M configurations,
    their fidelity, and what was noticed on the way."""

    layout: GuidedLayout
    configurations: tuple[Configuration, ...]
    fidelity: tuple[Fidelity, ...]
    warnings: tuple[str, ...]


