"""The dining room's Gymnasium spaces, bounded by the scene they describe.

Observations are in physical units (room frame, metres and radians), each ``Box`` bounded
by what the room allows: positions by its floor ``[0, width] x [0, depth]``, angles by
``[-pi, pi]``, heights by its tables and the episode's objects. The action's ``pose`` is
normalised to ``[-1, 1]`` per axis, as Gymnasium recommends for continuous actions: -1 and
+1 are the ends of the frame the action works in (:class:`PoseFrame`), so a sampled pose
always lies on the room's floor (navigate) or within the target table top's bounding box
(place; a round top's square).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from gymnasium import spaces

from llm_grop.errors import BadInput
from llm_grop.world.arrangement import Item
from llm_grop.world.scene import Scene


@dataclass(frozen=True)
class PoseFrame:
    """The extent a normalised ``pose`` action spans in one frame: ``low`` and ``high``
    are ``(x, y, theta)`` in metres and radians; -1 maps to ``low`` and +1 to ``high``,
    linearly per axis. ``name`` says which frame, for messages."""

    name: str
    low: tuple[float, float, float]
    high: tuple[float, float, float]

    def to_physical(self, pose: np.ndarray | Sequence[float]) -> tuple[float, float, float]:
        """``(x, y, theta)`` in metres and radians for a normalised ``pose``."""
        u = np.asarray(pose, dtype=float)
        lo, hi = np.asarray(self.low), np.asarray(self.high)
        x, y, theta = lo + (u + 1.0) / 2.0 * (hi - lo)
        return float(x), float(y), float(theta)

    def to_normalised(self, x: float, y: float, theta: float) -> np.ndarray:
        """The normalised ``pose`` (float32) for ``(x, y, theta)`` in metres and radians.

        Raises :class:`BadInput` for a pose outside this frame's extent."""
        for axis, value, lo, hi in zip(("x", "y", "theta"), (x, y, theta), self.low,
                                       self.high, strict=True):
            if not lo <= value <= hi:
                unit = "rad" if axis == "theta" else "m"
                raise BadInput(f"{value:g} {unit} is outside the {self.name}'s "
                               f"[{lo:g}, {hi:g}] {unit}", param=axis)
        lo, hi = np.asarray(self.low), np.asarray(self.high)
        u = 2.0 * (np.array([x, y, theta]) - lo) / (hi - lo) - 1.0
        return np.clip(u, -1.0, 1.0).astype(np.float32)


def room_frame(scene: Scene) -> PoseFrame:
    """The room's floor, where navigation goals lie (room frame)."""
    return PoseFrame("room", (0.0, 0.0, -math.pi), (scene.width, scene.depth, math.pi))


def table_frame(scene: Scene) -> PoseFrame:
    """The target table's top, where places go (its own frame, origin at the centre; a
    round top's bounding square)."""
    box = scene.target_table.box
    return PoseFrame("target table's top", (-box.width / 2, -box.depth / 2, -math.pi),
                     (box.width / 2, box.depth / 2, math.pi))


def action_space(n: int) -> spaces.Dict:
    """What an agent may do with ``n`` objects: ``action`` (navigate, pick, place),
    ``object``, ``on`` (an object index, or ``n`` for the table) and the normalised
    ``pose``."""
    return spaces.Dict({
        "action": spaces.Discrete(3),
        "object": spaces.Discrete(n),
        "on": spaces.Discrete(n + 1),
        "pose": spaces.Box(-1.0, 1.0, (3,), dtype=np.float32),
    })


def max_object_height_m(scene: Scene, items: Sequence[Item]) -> float:
    """The highest an object's bottom can be, metres: on the tallest table top under all
    the others stacked, lifted from there by up to the arm's reach."""
    top = max(t.height for t in scene.tables)
    return top + sum(i.spec.height for i in items) + scene.robot.reach_max_m


def observation_space(scene: Scene, items: Sequence[Item], chairs: int,
                      image_size: tuple[int, int] | None = None) -> spaces.Dict:
    """What the robot observes in ``scene`` with ``items`` and ``chairs`` sensed chairs
    (and an ``image`` of ``image_size`` ``(width, height)`` pixels when given)."""
    n, w, d = len(items), scene.width, scene.depth
    pi = math.pi
    # A chair inside the room is no longer than the room's diagonal.
    side = math.hypot(w, d)
    obs: dict[str, spaces.Space[Any]] = {
        "robot": _box((0.0, 0.0, -pi), (w, d, pi)),
        "objects": _box((0.0, 0.0, 0.0, -pi), (w, d, max_object_height_m(scene, items), pi),
                        rows=n),
        "held": spaces.Discrete(n + 1),
        "on_table": spaces.MultiBinary(n),
        "chairs": _box((0.0, 0.0, 0.0, 0.0, -pi), (w, d, side, side, pi), rows=chairs),
    }
    if image_size is not None:
        obs["image"] = spaces.Box(0, 255, (image_size[1], image_size[0], 3), np.uint8)
    return spaces.Dict(obs)


def _box(low: Sequence[float], high: Sequence[float], rows: int | None = None
         ) -> spaces.Box:
    """A float32 box from per-column bounds, one row per thing when ``rows`` is given."""
    lo, hi = np.array(low, np.float32), np.array(high, np.float32)
    if rows is not None:
        lo, hi = np.tile(lo, (rows, 1)), np.tile(hi, (rows, 1))
    return spaces.Box(lo, hi, dtype=np.float32)
