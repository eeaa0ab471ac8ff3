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
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Literal, Protocol, runtime_checkable

from llm_grop import seeds
from llm_grop.arrangement.pipeline import ArrangeOptions, arrange_items
from llm_grop.arrangement.random_placement import DrawBoxChoice, random_configurations
from llm_grop.errors import BadInput
from llm_grop.execution.policy import BASELINE_MANIP_ATTEMPTS
from llm_grop.llm.base import CallLog
from llm_grop.planning.grop import choose
from llm_grop.settings.declared import NoOptions
from llm_grop.world.arrangement import Arrangement, Configuration, Item
from llm_grop.world.catalog import Catalog
from llm_grop.world.fidelity import Fidelity
from llm_grop.world.request import Request
from llm_grop.world.table import Table

if TYPE_CHECKING:
    import numpy as np

    from llm_grop.planning.grop import Candidate
    from llm_grop.planning.utility import PlanningContext


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


class ArrangementSource(Protocol):
    """Where a method's arrangement comes from: ``uses_llm`` says whether it asks the LLM
    (the episode then gives it one), :meth:`propose` makes the arrangement and the
    configurations to plan for."""

    uses_llm: bool

    def propose(self, inp: EpisodeInput) -> Proposal:
        """The arrangement and the configurations to plan for."""
        ...


class StandingChoice(Protocol):
    """How a method picks its standing positions, and which configuration to plan for."""

    def choose(self, ctx: PlanningContext, proposal: Proposal,
               rng: np.random.Generator) -> Candidate:
        """The configuration and standing positions to plan with, from ``proposal``'s
        configurations in ``ctx``; raises :class:`~llm_grop.errors.Infeasible` when
        none has a plan."""
        ...


@dataclass(frozen=True)
class RandomOptions:
    """The options of a method with a random arrangement.

    ``draw_box``: where its objects are drawn: ``authors``, the authors' box (centres
    within ±0.225 m of the diner's place centre), grown to the diner's whole place when it
    cannot hold the objects; ``place``, the diner's whole place from the start.
    """

    draw_box: DrawBoxChoice = "authors"


@runtime_checkable
class Method(Protocol):
    """A compared method: its name and description, and what it chooses, as typed parts:
    its ``arrangement`` (an :class:`ArrangementSource`), its standing positions
    (``standing_choice``, a :class:`StandingChoice`) and its attempts per pick and place
    when executing (``manip_attempts``). The episode runs these parts and interprets no
    flag of a method's.

    It declares its own options as ``Options``, a frozen dataclass (``--method-option
    KEY=VALUE``), and :meth:`with_options` gives the method with a checked instance of it.
    """

    name: str
    description: str

    @property
    def Options(self) -> type:  # noqa: N802 - named as simulators and backends name it
        """The dataclass of its options."""
        ...

    def with_options(self, options: Any) -> Method:
        """This method with ``options`` (an instance of :attr:`Options`)."""
        ...

    @property
    def arrangement(self) -> ArrangementSource:
        """Where its arrangement comes from."""
        ...

    @property
    def standing_choice(self) -> StandingChoice:
        """How it picks standing positions."""
        ...

    @property
    def manip_attempts(self) -> int:
        """Attempts per pick and per place of each object when executing."""
        ...


@dataclass(frozen=True)
class LLMArrangement:
    """The paper's arrangement (§III-A, §III-B): the LLM's relations made consistent and
    M configurations sampled around its positions."""

    uses_llm: bool = True

    def propose(self, inp: EpisodeInput) -> Proposal:
        t0 = time.perf_counter()
        if inp.llm is None:
            raise BadInput("this method needs an LLM", param="method")
        before = inp.llm.wall_s
        result = arrange_items(inp.reading or inp.request, inp.items, inp.llm, inp.catalog,
                               inp.table, inp.seed, inp.options, inp.on_event)
        llm_s = inp.llm.wall_s - before
        return Proposal(result.arrangement, result.configurations,
                        max(time.perf_counter() - t0 - llm_s, 0.0), result.fidelity)


@dataclass(frozen=True)
class RandomArrangement:
    """The baselines' arrangement: M collision-free random configurations, drawn from
    the seed's ``random_arrangement`` stream, in the ``box`` the method's options name."""

    uses_llm: bool = False
    box: DrawBoxChoice = "authors"

    def propose(self, inp: EpisodeInput) -> Proposal:
        t0 = time.perf_counter()
        rng = seeds.stream(inp.seed, "random_arrangement")
        configs = random_configurations(inp.items, inp.table, rng, m=inp.options.m,
                                        box=self.box)
        arrangement = Arrangement(inp.request, inp.table, configs[0].placements)
        return Proposal(arrangement, configs, time.perf_counter() - t0)


@dataclass(frozen=True)
class PolicyStanding:
    """Standing positions by a policy of the planner's (:func:`~llm_grop.planning.grop.choose`):
    ``utility`` (GROP's, the best expected utility) or ``uniform`` (at random among those
    within good reach); ``best_of_all`` plans for every configuration and keeps the best,
    else the first that has a plan."""

    policy: Literal["utility", "uniform"] = "utility"
    best_of_all: bool = True

    def __post_init__(self) -> None:
        if self.policy not in ("utility", "uniform"):
            raise BadInput(f"standing must be 'utility' or 'uniform', got {self.policy!r}",
                           param="method")

    def choose(self, ctx: PlanningContext, proposal: Proposal,
               rng: np.random.Generator) -> Candidate:
        return choose(ctx, proposal.configurations, self.policy, rng, self.best_of_all,
                      proposal.fidelity)


@dataclass(frozen=True)
class ComposedMethod:
    """A method built from an arrangement source and a standing policy, declared in a line.

    ``uses_llm``: arrangement from the LLM pipeline (:class:`LLMArrangement`), else random
    (:class:`RandomArrangement`). ``standing``: ``utility`` (GROP) or ``uniform``.
    ``best_of_all``: plan for all M configurations and keep the best (GROP), else the
    first that has a plan. ``manip_attempts``: attempts per pick and per place when
    executing (the authors gave LLM-GROP 20 and the baselines 10).
    """

    name: str
    description: str
    uses_llm: bool
    standing: Literal["utility", "uniform"]
    best_of_all: bool
    manip_attempts: int = BASELINE_MANIP_ATTEMPTS
    #: Its options, an instance of :attr:`Options` (``None``: their defaults).
    options: Any = None

    def __post_init__(self) -> None:
        self.standing_choice  # noqa: B018 - a bad standing policy is refused when declared

    @property
    def Options(self) -> type:  # noqa: N802 - named as simulators and backends name it
        """:class:`RandomOptions` for a random arrangement; the LLM's takes none."""
        return NoOptions if self.uses_llm else RandomOptions

    def with_options(self, options: Any) -> ComposedMethod:
        """This method with ``options``."""
        return replace(self, options=options)

    @property
    def arrangement(self) -> ArrangementSource:
        """The LLM's arrangement or a random one."""
        if self.uses_llm:
            return LLMArrangement()
        options = self.options if self.options is not None else RandomOptions()
        return RandomArrangement(box=options.draw_box)

    @property
    def standing_choice(self) -> StandingChoice:
        """The standing policy, as declared."""
        return PolicyStanding(self.standing, self.best_of_all)


@dataclass(frozen=True)
class GivenArrangement:
    """A method planning for an arrangement it is given (a robot stack's, or one written
    by ``llm-grop arrange``): that one configuration as it is, with ``base``'s standing
    positions and attempt counts; no LLM is asked and nothing is sampled."""

    base: Method
    given: Arrangement
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
    def arrangement(self) -> ArrangementSource:
        """The given arrangement, as it is."""
        return self

    @property
    def standing_choice(self) -> StandingChoice:
        """The base method's standing positions."""
        return self.base.standing_choice

    @property
    def manip_attempts(self) -> int:
        """Attempts per pick and place: the base method's."""
        return self.base.manip_attempts

    @property
    def Options(self) -> type:  # noqa: N802 - named as simulators and backends name it
        """None: the arrangement is given."""
        return NoOptions

    def with_options(self, options: Any) -> GivenArrangement:
        """This method, unchanged: a given arrangement takes no options."""
        return self

    def propose(self, inp: EpisodeInput) -> Proposal:
        return Proposal(self.given, (Configuration(self.given.placements),), 0.0)
