"""What the rater reads and reports: the checked objects, and one check's outcome.

:func:`read_setting` turns the contract's arrangement JSON (a dict, possibly written
by hand or by another system) into :class:`Setting`. It reads ``request``,
``table`` and ``objects`` only, never ``relations`` or ``llm``. A malformed field
raises :class:`~llm_grop.errors.BadInput` with one line naming it.

Units: metres and radians in the table frame (origin at the table-top centre, +x to
the diner's right, +y away from the diner, who sits at the -y edge).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any, Literal

from shapely.geometry import Point, Polygon
from shapely.geometry.base import BaseGeometry

from llm_grop.errors import BadInput
from llm_grop.evaluation.conventions import Conventions
from llm_grop.world.catalog import Catalog, normalize_name

Severity = Literal["missing", "major", "minor"]
SEVERITIES: tuple[Severity, ...] = ("missing", "major", "minor")

_NUMBERED = re.compile(r"\s+\d+$")


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

    def to_dict(self) -> dict[str, Any]:
        """The check as a JSON-ready dict."""
        return asdict(self)


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

    ``width`` x ``depth`` is the table top (metres); ``support`` maps every object
    to what it rests on (``None``: the table), from ``on`` or, when ``on`` is
    absent, inferred for an allowed pair from a centre inside the other's
    footprint. ``requested`` holds the requested kinds (``None``: not known).
    """

    width: float
    depth: float
    objects: tuple[Obj, ...]
    support: Mapping[str, str | None]
    inferred: frozenset[str]
    requested: tuple[str, ...] | None
    conv: Conventions

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
    base = _NUMBERED.sub("", normalize_name(name))
    spec = catalog.lookup(base)
    return spec.name if spec is not None else base


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise BadInput(f"{where}: expected a number, got {value!r}")
    if not math.isfinite(value):
        raise BadInput(f"{where}: must be finite, got {value!r}")
    return float(value)


def _size(value: Any, where: str) -> tuple[float, float]:
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise BadInput(f"{where}: expected [sx, sy] in metres, got {value!r}")
    sx, sy = (_number(v, f"{where}[{i}]") for i, v in enumerate(value))
    if sx <= 0 or sy <= 0:
        raise BadInput(f"{where}: sizes must be positive, got {list(value)!r}")
    return sx, sy


def footprint(x: float, y: float, yaw: float, shape: str, size: tuple[float, float]
              ) -> BaseGeometry:
    """The footprint polygon in the table frame (a circle of diameter ``size[0]``, or a
    ``size`` box turned by ``yaw`` radians counter-clockwise)."""
    if shape == "circle":
        return Point(x, y).buffer(size[0] / 2, quad_segs=32)
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy = size[0] / 2, size[1] / 2
    return Polygon([(x + c * u - s * v, y + s * u + c * v)
                    for u, v in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))])


def _read_object(i: int, o: Any, where: str, catalog: Catalog) -> Obj:
    at = f"{where}: objects[{i}]"
    if not isinstance(o, Mapping):
        raise BadInput(f"{at}: expected an object with name, x, y, shape and size")
    if "name" not in o:
        raise BadInput(f"{at}.name: missing")
    name = o["name"]
    if not isinstance(name, str) or not name.strip():
        raise BadInput(f"{at}.name: expected a non-empty string, got {name!r}")
    at = f"{at} ({name!r})"
    raw_kind = o.get("kind", name)
    if not isinstance(raw_kind, str) or not raw_kind.strip():
        raise BadInput(f"{at}.kind: expected a non-empty string, got {raw_kind!r}")
    kind = kind_of(raw_kind, catalog)
    for key in ("x", "y"):
        if key not in o:
            raise BadInput(f"{at}.{key}: missing")
    x, y = _number(o["x"], f"{at}.x"), _number(o["y"], f"{at}.y")
    yaw = _number(o.get("yaw", 0.0), f"{at}.yaw")
    spec = catalog.lookup(kind)
    if "shape" in o:
        shape = o["shape"]
        if shape not in ("circle", "box"):
            raise BadInput(f"{at}.shape: must be 'circle' or 'box', got {shape!r}")
    elif spec is not None:
        shape = spec.shape
    else:
        raise BadInput(f"{at}.shape: missing (and {kind!r} is not in the catalog)")
    if "size" in o:
        size = _size(o["size"], f"{at}.size")
    elif spec is not None and spec.shape == shape:
        size = spec.size
    else:
        raise BadInput(f"{at}.size: missing")
    if shape == "circle" and abs(size[0] - size[1]) > 1e-6:
        raise BadInput(f"{at}.size: a circle needs [d, d], got {list(size)!r}")
    on = o.get("on")
    if on is not None and (not isinstance(on, str) or not on.strip()):
        raise BadInput(f"{at}.on: expected an object name or null, got {on!r}")
    return Obj(name, kind, x, y, yaw, shape, size, on, footprint(x, y, yaw, shape, size))


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


def read_setting(data: Any, requested: tuple[str, ...] | None, catalog: Catalog,
                 conv: Conventions, where: str = "arrangement") -> Setting:
    """A :class:`Setting` from the arrangement JSON ``data`` (``relations``/``llm`` unread)."""
    if not isinstance(data, Mapping):
        raise BadInput(f"{where}: expected a JSON object with 'table' and 'objects'")
    table = data.get("table")
    if not isinstance(table, Mapping):
        raise BadInput(f"{where}: table: missing, or not an object with a 'size'")
    shape = table.get("shape", "rectangle")
    if shape != "rectangle":
        raise BadInput(f"{where}: table.shape: only 'rectangle' is supported, got {shape!r}")
    if "size" not in table:
        raise BadInput(f"{where}: table.size: missing")
    width, depth = _size(table["size"], f"{where}: table.size")
    raw = data.get("objects")
    if not isinstance(raw, list):
        raise BadInput(f"{where}: objects: expected a list, got {type(raw).__name__}")
    objects = tuple(_read_object(i, o, where, catalog) for i, o in enumerate(raw))
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
    return Setting(width, depth, objects, support, frozenset(inferred), requested, conv)
