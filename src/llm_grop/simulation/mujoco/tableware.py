"""Tableware as rigid bodies: what each kind is made of, what it looks like and how the
gripper holds it.

Footprints and heights come from the plan's placements (the catalog); style, mass,
friction and look come from ``assets/tableware.yaml``, the looks themselves from
``assets/looks.yaml`` (:mod:`llm_grop.simulation.mujoco.looks`). All lengths in metres,
masses in kilograms, angles in radians; an object's own frame has its origin at the centre
of its footprint, on its bottom face, +x along the catalog's ``sx``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Literal

import mujoco
from pydantic import BaseModel, ConfigDict, Field

from llm_grop.datafile import load_yaml_model
from llm_grop.errors import BadInput
from llm_grop.simulation.mujoco import looks
from llm_grop.world.arrangement import Placement

Style = Literal["plate", "cylinder", "mug", "disk", "box", "bread", "berry"]

#: The gripper's widest opening between its pads, metres (a Robotiq 2F-140 opens 0.14 m).
MAX_OPENING_M = 0.14
#: Widest plate or bowl whose rim the gripper may pinch and the arm carry, metres.
MAX_RIM_DIAMETER_M = 0.40
#: Tallest object the fingers can hold upright, metres.
MAX_HEIGHT_M = 0.30
#: Half height of a finger pad, metres (robot.xml).
PAD_HALF_HEIGHT_M = 0.012
#: Pads stay this far above the support of most objects, metres ...
PAD_CLEAR_M = 0.001
#: ... but aim this far below it on an object at most :data:`THIN_M` tall (a mat), sliding
#: on the surface, so that they close on its edge even when the arm stops a few
#: millimetres high, and not on its top.
PAD_PRESS_M = 0.002
THIN_M = 0.006
#: Rim segments of a plate or bowl.
RIM_SEGMENTS = 12

#: Collision bits (robot.xml): tableware collides with furniture, robot, tableware, floor.
CONTYPE, CONAFFINITY = 4, 1 | 2 | 4 | 8


class _KindModel(BaseModel):
    model_config = ConfigDict(extra="forbid")
    style: Style
    mass: float = Field(gt=0)
    friction: tuple[float, float, float] | None = None
    look: str | None = None


class _DefaultModel(BaseModel):
    model_config = ConfigDict(extra="forbid")
    density: float = Field(gt=0)
    friction: tuple[float, float, float]
    looks: dict[Style, str] = {}


class _FileModel(BaseModel):
    model_config = ConfigDict(extra="forbid")
    default: _DefaultModel
    kinds: dict[str, _KindModel]


@cache
def _table() -> _FileModel:
    text = resources.files("llm_grop.simulation.mujoco").joinpath(
        "assets/tableware.yaml").read_text(encoding="utf-8")
    table = load_yaml_model(text, "tableware.yaml", _FileModel, "kinds", "style")
    named = [*table.default.looks.values(), *(k.look for k in table.kinds.values() if k.look)]
    unknown = sorted(set(named) - set(looks.names()))
    if unknown:
        raise BadInput(f"tableware.yaml: looks {', '.join(unknown)} are not in looks.yaml")
    return table


@dataclass(frozen=True)
class Grasp:
    """Where the pads close on an object, in the object's own frame.

    ``point`` is the midpoint between the pads (metres); ``axis_yaw`` the direction the
    pads close along (radians, about the object's z); ``width`` the object's extent
    between the pads (metres).
    """

    point: tuple[float, float, float]
    axis_yaw: float
    width: float


@dataclass(frozen=True)
class Tableware:
    """One physical object: its catalog footprint ``size`` (metres), ``height`` (metres),
    ``style``, ``mass`` (kg), ``friction`` (MuJoCo's three coefficients) and ``look`` (a
    look of ``assets/looks.yaml``; ``None``: drawn as its collision geoms)."""

    name: str
    kind: str
    shape: Literal["circle", "box"]
    size: tuple[float, float]
    height: float
    style: Style
    mass: float
    friction: tuple[float, float, float]
    look: str | None = None

    @property
    def radius(self) -> float:
        """Half the larger footprint side, metres."""
        return max(self.size) / 2

    def rim(self) -> tuple[float, float]:
        """A plate's rim: its width and the thickness of its base disk, metres."""
        r = self.size[0] / 2
        return min(0.03, 0.25 * r), min(0.006, self.height / 3)

    def grasps(self) -> tuple[Grasp, ...]:
        """Where the gripper may hold this object, best first (object frame).

        A plate is pinched on its rim, the two pads either side of one rim segment; it is
        listed at every segment, and the caller picks the one nearest the robot.
        """
        h = self.height
        if self.style == "plate":
            width, disk = self.rim()
            r_mid = self.size[0] / 2 - width / 2
            z = max(h / 2, disk + PAD_HALF_HEIGHT_M + PAD_CLEAR_M)
            return tuple(Grasp((r_mid * math.cos(a), r_mid * math.sin(a), z), a, width)
                         for a in (2 * math.pi * (k + 0.5) / RIM_SEGMENTS
                                   for k in range(RIM_SEGMENTS)))
        low = PAD_HALF_HEIGHT_M + (-PAD_PRESS_M if h <= THIN_M else PAD_CLEAR_M)
        z = max(h / 2 if h < 0.06 else h - 0.03, low)
        if self.shape == "circle":
            # The mug's handle points along +x, so the pads close across y.
            return (Grasp((0.0, 0.0, z), math.pi / 2, self.size[0]),
                    Grasp((0.0, 0.0, z), -math.pi / 2, self.size[0]))
        sx, sy = self.size
        yaw, width = (0.0, sx) if sx <= sy else (math.pi / 2, sy)
        return (Grasp((0.0, 0.0, z), yaw, width), Grasp((0.0, 0.0, z), yaw + math.pi, width))


def tableware(p: Placement) -> Tableware:
    """The physical object for a planned placement; :class:`BadInput` when the gripper
    cannot hold it."""
    table = _table()
    entry = table.kinds.get(p.kind)
    sx, sy = p.size
    h = p.height if p.height > 0 else 0.02
    look = None
    if entry is not None:
        style, mass, look = entry.style, entry.mass, entry.look
        friction = entry.friction or table.default.friction
    else:
        style = "cylinder" if p.shape == "circle" else "box"
        area = math.pi * sx * sx / 4 if p.shape == "circle" else sx * sy
        mass, friction = table.default.density * area * h, table.default.friction
    if style != "plate" and p.shape == "circle" and sx > MAX_OPENING_M:
        style = "plate"
    t = Tableware(p.name, p.kind or p.name, p.shape, (sx, sy), h, style, mass,
                  tuple(friction),  # type: ignore[arg-type]
                  look or table.default.looks.get(style))
    narrow = min(sx, sy)
    too_wide = (narrow > MAX_OPENING_M and not (style == "plate" and p.shape == "circle")) \
        or (style == "plate" and sx > MAX_RIM_DIAMETER_M)
    if too_wide or h > MAX_HEIGHT_M:
        what = f"{sx:.2f} x {sy:.2f} x {h:.2f} m"
        raise BadInput(f"object {p.name!r} ({what}): too large for the gripper, which opens "
                       f"{MAX_OPENING_M:.2f} m, pinches rims of plates up to "
                       f"{MAX_RIM_DIAMETER_M:.2f} m and holds objects up to {MAX_HEIGHT_M:.2f} m "
                       "tall")
    return t


def add_body(spec: mujoco.MjSpec, parent: mujoco.MjsBody, t: Tableware,
             pos: tuple[float, float, float], yaw: float,
             rgba: tuple[float, float, float, float]) -> mujoco.MjsBody:
    """Add ``t`` to ``spec`` as a free body under ``parent`` with its bottom centre at
    ``pos`` (metres, world frame) turned by ``yaw``, coloured ``rgba``; its mass is spread
    over its collision geoms by volume. With a look, those are hidden
    (:data:`~llm_grop.simulation.mujoco.looks.GROUP_COLLISION`) and the look is drawn."""
    body = parent.add_body(name=t.name, pos=list(pos),
                           quat=[math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)])
    body.add_freejoint(name=t.name)
    visuals = looks.visuals(t.look, t.size, t.height) if t.look else ()
    geoms = list(_geoms(t))
    volume = sum(v for *_, v in geoms)
    for k, (gtype, size, gpos, gyaw, v) in enumerate(geoms):
        body.add_geom(name=f"{t.name}#{k}", type=gtype, size=list(size), pos=list(gpos),
                      quat=[math.cos(gyaw / 2), 0, 0, math.sin(gyaw / 2)],
                      mass=t.mass * v / volume, friction=list(t.friction), rgba=list(rgba),
                      contype=CONTYPE, conaffinity=CONAFFINITY,
                      group=looks.GROUP_COLLISION if visuals else looks.GROUP_VISUAL,
                      # A berry is round: rolling friction (condim 6) keeps it where it
                      # is put, as a real strawberry's shape does.
                      condim=6 if t.style == "berry" else 4,
                      solref=[0.004, 1.0], priority=1)
    looks.add_look(spec, body, t.name, visuals, rgba)
    return body


_G = mujoco.mjtGeom


def _geoms(t: Tableware):  # noqa: ANN202 - (type, size, pos, yaw, volume) tuples
    """The geoms of ``t`` in its body frame: ``(type, size, pos, yaw, volume)``."""
    sx, sy = t.size
    h = t.height
    if t.style == "plate":
        r = sx / 2
        width, disk = t.rim()
        yield _G.mjGEOM_CYLINDER, (r - width / 2, disk / 2, 0), (0, 0, disk / 2), 0.0, \
            math.pi * (r - width / 2) ** 2 * disk
        r_mid = r - width / 2
        half_len = r_mid * math.tan(math.pi / RIM_SEGMENTS) + width / 4
        for k in range(RIM_SEGMENTS):
            a = 2 * math.pi * (k + 0.5) / RIM_SEGMENTS
            yield _G.mjGEOM_BOX, (width / 2, half_len, h / 2), \
                (r_mid * math.cos(a), r_mid * math.sin(a), h / 2), a, 2 * half_len * width * h
    elif t.style in ("cylinder", "disk"):
        yield _G.mjGEOM_CYLINDER, (sx / 2, h / 2, 0), (0, 0, h / 2), 0.0, math.pi * sx**2 / 4 * h
    elif t.style == "mug":
        r = sx / 2
        yield _G.mjGEOM_CYLINDER, (r, h / 2, 0), (0, 0, h / 2), 0.0, math.pi * r * r * h
        yield _G.mjGEOM_BOX, (0.012, 0.006, h * 0.22), (r + 0.010, 0, h * 0.6), 0.0, \
            0.024 * 0.012 * h * 0.44
    elif t.style == "berry":
        yield _G.mjGEOM_ELLIPSOID, (sx / 2, sy / 2, h / 2), (0, 0, h / 2), 0.0, \
            4 / 3 * math.pi * sx * sy * h / 8
    elif t.style == "bread":
        yield _G.mjGEOM_BOX, (sx / 2, sy / 2, h * 0.35), (0, 0, h * 0.35), 0.0, sx * sy * h * 0.7
        yield _G.mjGEOM_BOX, (sx / 2 - 0.01, sy / 2 - 0.01, h * 0.15), (0, 0, h * 0.85), 0.0, \
            (sx - 0.02) * (sy - 0.02) * h * 0.3
    else:
        yield _G.mjGEOM_BOX, (sx / 2, sy / 2, h / 2), (0, 0, h / 2), 0.0, sx * sy * h
