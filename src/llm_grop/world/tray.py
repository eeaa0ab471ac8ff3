"""The robot's tray, as its MJCF file declares it (``tray.xml`` beside this module), read
without MuJoCo: both simulators carry alike from it (the MuJoCo world attaches that very
file to the base) and the planner groups objects into trips that fit it. It says how many
objects the tray holds, how high its top is, and its slots, where the arm puts objects
down.

An object fits a slot when its footprint lies inside the slot's rectangle: a round one
within the slot's shorter side, a long one along its longer side. A trip's objects fit the
tray together when each can have a slot of its own (:meth:`Tray.assign`).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from importlib import resources
from importlib.resources.abc import Traversable

from llm_grop.errors import BadInput

#: The tray's MJCF file, beside this module (package data of :mod:`llm_grop.world`).
TRAY_XML = "tray.xml"


@dataclass(frozen=True)
class Slot:
    """A place on the tray: its centre ``(x, y)`` in the base's frame (metres, x forward)
    and its rectangle's half sizes along the base's x and y (metres)."""

    x: float
    y: float
    half_x: float
    half_y: float

    def yaw(self, shape: str, size: tuple[float, float]) -> float | None:
        """The yaw (base frame, radians) at which an object of footprint ``shape`` and
        ``size`` (its own frame, metres) lies in this slot, ``None`` when it does not fit:
        0 for a round one; a long one lies along the slot's longer side."""
        short, long_ = sorted((self.half_x, self.half_y))
        if shape == "circle":
            return 0.0 if size[0] / 2 <= short + 1e-9 else None
        small, big = sorted(size)
        if small / 2 > short + 1e-9 or big / 2 > long_ + 1e-9:
            return None
        # The object's longer side along the slot's longer side.
        along_x = self.half_x >= self.half_y
        return 0.0 if (size[0] >= size[1]) == along_x else math.pi / 2

    @property
    def area_m2(self) -> float:
        """The slot's area, square metres."""
        return 4 * self.half_x * self.half_y


@dataclass(frozen=True)
class Tray:
    """The tray: ``capacity`` (how many objects it holds), ``top_z_m`` (its top's height
    above the floor, metres), ``radius_m`` (inside its rim, metres) and its ``slots``."""

    capacity: int
    top_z_m: float
    radius_m: float
    slots: tuple[Slot, ...]

    def assign(self, footprints: Sequence[tuple[str, tuple[float, float]]],
               taken: Sequence[int] = ()) -> tuple[int, ...] | None:
        """A slot for each footprint (``(shape, size)``, in order), none in ``taken`` and
        no two alike, preferring small slots; ``None`` when they do not all fit or are more
        than the tray holds."""
        if len(footprints) + len(taken) > self.capacity:
            return None
        order = sorted(range(len(self.slots)), key=lambda k: self.slots[k].area_m2)

        def place(i: int, used: frozenset[int]) -> tuple[int, ...] | None:
            if i == len(footprints):
                return ()
            shape, size = footprints[i]
            for k in order:
                if k not in used and self.slots[k].yaw(shape, size) is not None:
                    rest = place(i + 1, used | {k})
                    if rest is not None:
                        return (k, *rest)
            return None

        return place(0, frozenset(taken))


@cache
def load_tray() -> Tray:
    """The packaged tray (``world/tray.xml``); its file is read once."""
    return tray_from_xml(tray_xml_path().read_text(), f"world/{TRAY_XML}")


def tray_xml_path() -> Traversable:
    """The packaged tray's MJCF file (the MuJoCo world builds the tray from it)."""
    return resources.files("llm_grop.world").joinpath(TRAY_XML)


def tray_from_xml(text: str, where: str) -> Tray:
    """The tray an MJCF text declares: its ``tray_capacity`` numeric, its ``tray`` body
    (whose origin is its top's centre), its ``tray_top`` cylinder and its ``slot:K``
    sites. :class:`BadInput` naming ``where`` when one is missing or malformed."""
    try:
        root = ET.fromstring(text)
        numeric = root.find("./custom/numeric[@name='tray_capacity']")
        body = root.find(".//body[@name='tray']")
        if numeric is None or body is None:
            raise ValueError("needs a tray_capacity numeric and a tray body")
        capacity = int(float(numeric.get("data", "")))
        top_z = float(body.get("pos", "0 0 0").split()[2])
        top = body.find("./geom[@name='tray_top']")
        if top is None:
            raise ValueError("needs a tray_top geom")
        rim = root.find(".//default[@class='tray_rim']/geom")
        rims = [g for g in body.findall("./geom") if (g.get("name") or "").startswith("tray_rim")]
        if rim is None or not rims:
            raise ValueError("needs tray_rim geoms and their default class")
        # Inside the rim: the rim's centre line less half its thickness.
        centre = max(math.hypot(*(float(v) for v in g.get("pos", "").split()[:2])) for g in rims)
        radius = centre - float(rim.get("size", "").split()[0])
        slots = []
        for site in body.findall("./site"):
            if not (site.get("name") or "").startswith("slot:"):
                continue
            x, y, _ = (float(v) for v in site.get("pos", "").split())
            hx, hy = (float(v) for v in site.get("size", "").split()[:2])
            slots.append(Slot(x, y, hx, hy))
    except (ValueError, IndexError, ET.ParseError) as exc:
        raise BadInput(f"{where}: {exc}") from None
    if capacity < 1 or capacity > len(slots):
        raise BadInput(f"{where}: tray_capacity must be between 1 and its {len(slots)} slots, "
                       f"got {capacity}")
    return Tray(capacity, top_z, radius, tuple(slots))
