"""What a method is: where its arrangement comes from and how it picks standing positions.

The four methods of the paper differ in exactly two choices and share everything else
(sequencing, navigation, simulator):

========== ============================ ===========================================
method     arrangement                  standing positions
========== ============================ ===========================================
tpra       random, collision-free       uniform among those within good reach
latp       the LLM's (§III-A, §III-B)   uniform among those within good reach
grop       random, collision-free       utility-optimal over M configurations
llm-grop   the LLM's                    utility-optimal over M configurations
========== ============================ ===========================================
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, Protocol

from llm_grop import seeds
from llm_grop.arrangement.pipeline import ArrangeOptions, arrange_items
from llm_grop.arrangement.random_placement import random_configurations
from llm_grop.errors import BadInput
from llm_grop.execution.policy import BASELINE_MANIP_ATTEMPTS
from llm_grop.llm.base import CallLog
from llm_grop.world.arrangement import Arrangement, Configuration, Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.fidelity import Fidelity
from llm_grop.world.request import Request
from llm_grop.world.table import Table


@dataclass(frozen=True)
class EpisodeInput:
    """What a method is given: the request and its items, the table to set, the seed, and
    an LLM (``None`` for methods that use none)."""

    request: str
    items: tuple[Item, ...]
    table: Table
    seed: int
    catalog: Catalog
    llm: CallLog | None = None
    options: ArrangeOptions = ArrangeOptions()
    on_event: Callable[[str], None] | None = None
    #: How the request was read: the relations it states and the LLM calls that read it.
    reading: Request | None = None


@dataclass(frozen=True)
class Proposal:
    """A method's arrangement: the one shown (first configuration), the M configurations
    to plan for, the seconds spent computing them with LLM calls excluded, and how
    faithfully each configuration keeps the stated geometry (empty: nothing was stated,
    as for a random arrangement)."""

    arrangement: Arrangement
    configurations: tuple[Configuration, ...]
    compute_time_s: float
    fidelity: tuple[Fidelity, ...] = ()


class Method(Protocol):
    """A compared method."""

    name: str
    description: str
    uses_llm: bool
    standing: Literal["utility", "uniform"]
    best_of_all: bool

    def propose(self, inp: EpisodeInput) -> Proposal:
        """The arrangement and the configurations to plan for."""
        ...


@dataclass(frozen=True)
class ComposedMethod:
    """A method built from an arrangement source and a standing policy.

    ``uses_llm``: arrangement from the LLM pipeline, else random. ``standing``: ``utility``
    (GROP) or ``uniform``. ``best_of_all``: plan for all M configurations and keep the best
    (GROP), else the first that has a plan. ``manip_attempts``: attempts per pick and per
    place when executing (the authors gave LLM-GROP 20 and the baselines 10); a method
    without it gets the baselines' count.
    """

    name: str
    description: str
    uses_llm: bool
    standing: Literal["utility", "uniform"]
    best_of_all: bool
    manip_attempts: int = BASELINE_MANIP_ATTEMPTS

    def propose(self, inp: EpisodeInput) -> Proposal:
        t0 = time.perf_counter()
        if self.uses_llm:
            if inp.llm is None:
                raise BadInput(f"method {self.name!r} needs an LLM")
            before = inp.llm.wall_s
            result = arrange_items(inp.reading or inp.request, inp.items, inp.llm,
                                   inp.catalog, inp.table, inp.seed, inp.options,
                                   inp.on_event)
            llm_s = inp.llm.wall_s - before
            return Proposal(result.arrangement, result.configurations,
                            max(time.perf_counter() - t0 - llm_s, 0.0), result.fidelity)
        rng = seeds.stream(inp.seed, "random_arrangement")
        configs = random_configurations(inp.items, inp.table, rng, m=inp.options.m)
        arrangement = Arrangement(inp.request, inp.table, configs[0].placements)
        return Proposal(arrangement, configs, time.perf_counter() - t0)



@dataclass(frozen=True)
class GivenArrangement:
    """A method planning for an arrangement it is given (a robot stack's, or one written
    by ``llm-grop arrange``): that one configuration as it is, with ``base``'s standing
    positions and attempt counts; no LLM is asked and nothing is sampled."""

    base: Method
    arrangement: Arrangement
    uses_llm: bool = False

    @property
    def name(self) -> str:
        """The base method's name."""
        return self.base.name

    @property
    def description(self) -> str:
        """What it does, in words."""
        return f"{self.base.name} planning for a given arrangement"

    @property
    def standing(self) -> Literal["utility", "uniform"]:
        """The base method's standing policy."""
        return self.base.standing

    @property
    def best_of_all(self) -> bool:
        """Whether the base method plans for every configuration (there is one here)."""
        return self.base.best_of_all

    @property
    def manip_attempts(self) -> int:
        """Attempts per pick and place: the base method's."""
        return getattr(self.base, "manip_attempts", BASELINE_MANIP_ATTEMPTS)

    def propose(self, inp: EpisodeInput) -> Proposal:
        return Proposal(self.arrangement, (Configuration(self.arrangement.placements),), 0.0)
