"""What the rater reads and reports: the checked objects, and one check's outcome.

:func:`read_setting` turns the contract's arrangement document (validated by
:class:`~llm_grop.contract.models.ArrangementDoc`, possibly written by hand or by another
system) into :class:`Setting`. It uses ``table`` and ``objects`` only, never
``relations`` or ``llm``. What the contract's model cannot check (a name used twice, a
support that is not there, a circle that is not round) raises
:class:`~llm_grop.errors.BadInput` with one line naming the field.

Units: metres and radians in the table frame (origin at the table-top centre, +x to
the diner's right, +y away from the diner, who sits at the -y edge).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

from shapely.geometry import Point, Polygon
from shapely.geometry.base import BaseGeometry

from llm_grop.contract.models import ArrangementDoc, ObjectDoc
from llm_grop.errors import BadInput
from llm_grop.evaluation.conventions import Conventions
from llm_grop.geometry.footprint import footprint
from llm_grop.world.arrangement import UPRIGHT_TILT_RAD
from llm_grop.world.catalog import Catalog, instance_kind, normalize_name

Severity = Literal["missing", "major", "minor"]
SEVERITIES: tuple[Severity, ...] = ("missing", "major", "minor")


@dataclass(frozen=True)
class Check:
    """One rule applied to the arrangement.

    ``severity`` is what a failure costs (``missing``: score 1; ``major``; ``minor``).
    A passed check carries the worst severity its rule can give. ``detail`` names
    the objects and the measured values. ``skipped`` marks a rule that did not
    apply (its reference object is absent); a skipped check counts as passed.
    """

    name: str
    passed: bool
    severity: Severity
    detail: str
    skipped: bool = False


@dataclass(frozen=True)
class Obj:
    """One object of the arrangement, with its footprint.

    ``kind`` is the catalog name (from the JSON's ``kind``, else the name without a
    trailing number); ``on`` is the support the JSON names (``None``: the table).
    """

    name: str
    kind: str
    x: float
    y: float
    yaw: float
    shape: Literal["circle", "box"]
    size: tuple[float, float]
    on: str | None
    footprint: BaseGeometry = field(compare=False, repr=False)
    tilt_rad: float = 0.0

    @property
    def upright(self) -> bool:
        """Whether it stands upright (an executed arrangement says how tilted it is)."""
        return self.tilt_rad <= UPRIGHT_TILT_RAD

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """Footprint ``(min x, min y, max x, max y)`` in metres."""
        b = self.footprint.bounds
        return (b[0], b[1], b[2], b[3])

    @property
    def bottom(self) -> float:
        """Lowest y of the footprint (the end nearest the diner), metres."""
        return self.bounds[1]

    def axis_deviation(self) -> float:
        """Radians between the object's long axis and the line of sight (+y), 0..pi/2."""
        base = 0.0 if self.size[1] >= self.size[0] else math.pi / 2
        d = (self.yaw + base) % math.pi
        return min(d, math.pi - d)


@dataclass(frozen=True)
class Setting:
    """The arrangement as the rules see it.

    ``width`` x ``depth`` is the table top (metres), or, for one of several diners, their
    place at it; the diner sits at its -y edge. ``support`` maps every object
    to what it rests on (``None``: the table), from ``on`` or, when ``on`` is
    absent, inferred for an allowed pair from a centre inside the other's
    footprint. ``requested`` holds the requested kinds (``None``: not known).
    ``outline`` is the whole table top in the setting's frame when it is not the
    ``width`` x ``depth`` rectangle (a round top, or a diner's place at a bigger table).
    """

    width: float
    depth: float
    objects: tuple[Obj, ...]
    support: Mapping[str, str | None]
    inferred: frozenset[str]
    requested: tuple[str, ...] | None
    conv: Conventions
    outline: Polygon | None = field(default=None, compare=False)

    def by_name(self, name: str) -> Obj:
        """The object called ``name``."""
        return next(o for o in self.objects if o.name == name)

    def with_role(self, role: str) -> list[Obj]:
        """Objects whose kind plays ``role``, in JSON order."""
        return [o for o in self.objects if self.conv.has_role(o.kind, role)]

    def on_table(self, o: Obj) -> bool:
        """Whether ``o`` rests directly on the table."""
        return self.support[o.name] is None

    def stack_of(self, o: Obj) -> list[str]:
        """``o`` and everything below it, top down."""
        chain = [o.name]
        below = self.support[o.name]
        while below is not None and below not in chain:
            chain.append(below)
            below = self.support[below]
        return chain


def kind_of(name: str, catalog: Catalog) -> str:
    """Catalog kind of an object or item name: trailing number dropped, synonyms resolved.

    ``"dinner fork 2"`` and ``"fork"`` give ``"dinner fork"``; an unknown name is
    returned normalised.
    """
    base = instance_kind(normalize_name(name))
    spec = catalog.lookup(base)
    return spec.name if spec is not None else base


def _read_object(i: int, o: ObjectDoc, where: str, catalog: Catalog) -> Obj:
    at = f"{where}: objects[{i}] ({o.name!r})"
    kind = kind_of(o.kind or o.name, catalog)
    spec = catalog.lookup(kind)
    if o.shape is not None:
        shape = o.shape
    elif spec is not None:
        shape = spec.shape
    else:
        raise BadInput(f"{at}.shape: missing (and {kind!r} is not in the catalog)")
    if o.size is not None:
        size = o.size
    elif spec is not None and spec.shape == shape:
        size = spec.size
    else:
        raise BadInput(f"{at}.size: missing")
    if shape == "circle" and abs(size[0] - size[1]) > 1e-6:
        raise BadInput(f"{at}.size: a circle needs [d, d], got {list(size)!r}")
    return Obj(o.name, kind, o.x, o.y, o.yaw, shape, size, o.on,
               footprint(o.x, o.y, o.yaw, shape, size), o.tilt_rad or 0.0)


def _rests_on(name: str, other: str, support: Mapping[str, str | None]) -> bool:
    """Whether ``name`` rests, directly or not, on ``other`` (or is ``other``)."""
    seen: set[str] = set()
    below: str | None = name
    while below is not None and below not in seen:
        if below == other:
            return True
        seen.add(below)
        below = support[below]
    return False


def read_setting(doc: ArrangementDoc, requested: tuple[str, ...] | None, catalog: Catalog,
                 conv: Conventions, where: str = "arrangement",
                 outline: Polygon | None = None) -> Setting:
    """A :class:`Setting` from the arrangement document ``doc`` (a round top's outline is
    a circle; ``outline`` overrides it, e.g. with the whole table seen from a diner's
    place)."""
    width, depth = doc.table.size
    if outline is None and doc.table.shape == "circle":
        outline = Point(0.0, 0.0).buffer(width / 2, quad_segs=32)
    objects = tuple(_read_object(i, o, where, catalog) for i, o in enumerate(doc.objects))
    names = [o.name for o in objects]
    for i, o in enumerate(objects):
        if o.name in names[:i]:
            raise BadInput(f"{where}: objects[{i}].name: {o.name!r} is used twice")
        if o.on is not None and (o.on not in names or o.on == o.name):
            raise BadInput(f"{where}: objects[{i}] ({o.name!r}).on: {o.on!r} names no other "
                           "object of the arrangement")
    support: dict[str, str | None] = {o.name: o.on for o in objects}
    inferred: set[str] = set()
    for o in objects:
        if o.on is not None:
            continue
        centre = Point(o.x, o.y)
        hosts = [h for h in objects if h is not o and conv.may_rest_on(o.kind, h.kind)
                 and h.footprint.covers(centre) and not _rests_on(h.name, o.name, support)]
        if hosts:
            support[o.name] = hosts[0].name
            inferred.add(o.name)
    for o in objects:  # a cycle of `on` can never stand
        seen = [o.name]
        below = support[o.name]
        while below is not None:
            if below in seen:
                raise BadInput(f"{where}: objects ({o.name!r}).on: objects rest on each other "
                               f"in a cycle ({' -> '.join([*seen, below])})")
            seen.append(below)
            below = support[below]
    return Setting(width, depth, objects, support, frozenset(inferred), requested, conv,
                   outline)
