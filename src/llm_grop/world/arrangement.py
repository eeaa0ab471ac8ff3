"""Where objects stand on the table: placements, configurations, arrangements."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from llm_grop.world.catalog import ObjectSpec
from llm_grop.world.failure import Revision
from llm_grop.world.llmlog import LLMSummary
from llm_grop.world.relation import Relation
from llm_grop.world.table import Table

#: Where a requested object came from: the request names it ("request"), the LLM chose
#: it because the request does not name it, or not how many ("llm"), or a task lists it.
ITEM_SOURCES: tuple[str, ...] = ("request", "llm", "task")


@dataclass(frozen=True)
class Item:
    """One requested object: an instance ``name`` of catalog kind ``spec``.

    The first instance of a kind is named after it ("dinner fork"); further ones
    get a number ("dinner fork 2"). ``diner`` is the index of the diner whose setting
    it belongs to (into the table's ``diners``), ``None`` for a request with one diner.
    ``source`` says where it came from (one of :data:`ITEM_SOURCES`: the request names it,
    the LLM chose it, or the paper's task lists it) and ``words`` the request's words it
    was read from.
    """

    name: str
    spec: ObjectSpec
    diner: int | None = None
    source: str = "request"
    words: str = ""

    @property
    def kind(self) -> str:
        """The catalog name of this item's kind."""
        return self.spec.name


@dataclass(frozen=True)
class Placement:
    """An object on the table, in the table frame.

    ``x``, ``y`` in metres; ``yaw`` in radians (object frame -> table frame,
    counter-clockwise); ``size`` is the footprint ``(sx, sy)`` in metres in the
    object's own frame; ``on`` names the object it rests on (``None``: the table);
    ``diner`` is the index of the diner whose setting it belongs to (``None``: one diner).
    After execution, ``z_m`` is the height of its base above the table top (metres) and
    ``tilt_rad`` the angle between its up axis and the vertical (radians); both are 0 for
    a planned placement.
    """

    name: str
    x: float
    y: float
    yaw: float
    shape: Literal["circle", "box"]
    size: tuple[float, float]
    on: str | None = None
    kind: str = ""
    height: float = 0.0
    diner: int | None = None
    z_m: float = 0.0
    tilt_rad: float = 0.0

    @property
    def upright(self) -> bool:
        """Whether it stands upright: tilted at most :data:`UPRIGHT_TILT_RAD`."""
        return self.tilt_rad <= UPRIGHT_TILT_RAD


#: Largest tilt, radians, of an object that still counts as upright (about 20 degrees):
#: the executive's default place tolerance and the rater's test for a tipped object.
UPRIGHT_TILT_RAD = 0.35


def item_placement(item: Item) -> Placement:
    """``item`` as a placement at the table's centre: its shape, footprint and height,
    for code that needs an object's dimensions before it has a place."""
    s = item.spec
    return Placement(item.name, 0.0, 0.0, 0.0, s.shape, s.size, None, s.name, s.height,
                     item.diner)


@dataclass(frozen=True)
class Configuration:
    """One feasible set of placements for every item (a sample of the sampler)."""

    placements: tuple[Placement, ...]

    def by_name(self) -> dict[str, Placement]:
        """Placements keyed by object name."""
        return {p.name: p for p in self.placements}


@dataclass(frozen=True)
class Arrangement:
    """The contract's arrangement: a table, placed objects and the relations they keep.

    ``warnings`` and ``conflicts`` record what the pipeline dropped or re-prompted, and
    ``revisions`` what the feedback loop told the LLM and what it answered.
    """

    request: str
    table: Table
    placements: tuple[Placement, ...]
    relations: tuple[Relation, ...] = ()
    llm: LLMSummary | None = None
    warnings: tuple[str, ...] = ()
    conflicts: tuple[tuple[Relation, ...], ...] = field(default=())
    #: How the request's objects were read: ``"catalog"``, ``"llm"``, or ``None`` unknown.
    read_by: str | None = None
    #: Where each object came from: ``(name, source, words)`` (see :class:`Item`).
    origins: tuple[tuple[str, str, str], ...] = ()
    #: The feedback loop's rounds: each failure told to the LLM and what came of it.
    revisions: tuple[Revision, ...] = ()
