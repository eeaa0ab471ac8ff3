"""Whether an object is in place: a physical state, read after the physics settles.

An object is in place when it is not in the hand, lies on the target table, stands
upright, rests on its intended support (the table, or the object it should be on) and
lies within tolerance of its target (the executive translates the target of an object that
goes on another with its support). Otherwise the first of these that fails says why.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np

from llm_grop.execution.policy import ExecutionPolicy
from llm_grop.geometry.footprint import footprint
from llm_grop.simulation.base import Session
from llm_grop.world.arrangement import Placement
from llm_grop.world.plan import ExecutedStep, ObjectState, Reason
from llm_grop.world.scene import Scene


def judge(state: ObjectState, target: tuple[float, float], on: str | None, scene: Scene,
          policy: ExecutionPolicy) -> Reason | None:
    """Why ``state`` is not in place at ``target`` ``(x, y)`` (table frame, metres) on
    ``on`` (``None``: the table), or ``None`` when it is."""
    if state.held or state.table is None:
        return "fell"
    if state.tilt_rad > policy.max_tilt_rad:
        return "tipped"
    if state.table != scene.target or state.on != on:
        return "wrong_support"
    if on is None and state.z - scene.target_table.height > policy.rest_m:
        return "wrong_support"
    goal = scene.table_to_room(*target)
    if math.hypot(state.x - goal.x, state.y - goal.y) > policy.max_offset_m:
        return "slid"
    return None


def judged_place(session: Session, scene: Scene, name: str, x: float, y: float, yaw: float,
                 on: str | None, policy: ExecutionPolicy,
                 target: tuple[float, float] | None = None) -> tuple[ExecutedStep, ObjectState]:
    """One place attempt of ``name`` at ``(x, y, yaw)`` (table frame) on ``on``, judged where
    the object came to rest against ``target`` (table frame, metres; ``None``: ``(x, y)``):
    a released object out of place makes the step fail with the reason. The step (its
    ``pose`` where the object lies, table frame) and the object's state."""
    done = session.place(name, x, y, yaw, on)
    state = session.objects()[name]
    goal = (x, y) if target is None else target
    if done.ok:
        why = judge(state, goal, on, scene, policy)
        if why is not None:
            done = replace(done, ok=False, reason=why, note=_words(why, state, goal, scene))
        done = replace(done, pose=table_pose(state, scene))
    return done, state


def _words(why: Reason, state: ObjectState, target: tuple[float, float], scene: Scene) -> str:
    """One line saying how a released object is out of place."""
    if why == "tipped":
        return f"it tipped over ({state.tilt_rad:.2f} rad from upright)"
    if why == "fell":
        return "it fell off the table"
    if why == "wrong_support":
        where = f"on the {state.on}" if state.on else "on the table"
        return f"it came to rest {where}, not on its intended support"
    x, y, _ = table_pose(state, scene)
    return (f"it came to rest {100 * math.hypot(x - target[0], y - target[1]):.1f} cm "
            "from its target")


def table_pose(state: ObjectState, scene: Scene) -> tuple[float, float, float]:
    """``state``'s ``(x, y, yaw)`` in the target table's frame (metres, radians)."""
    x, y, yaw = scene.room_to_table(state.x, state.y, state.yaw)
    return (round(x, 4), round(y, 4), round(yaw, 4))


def final_placements(states: Mapping[str, ObjectState], shapes: Sequence[Placement],
                     scene: Scene) -> tuple[Placement, ...]:
    """Every object of ``shapes`` resting on the target table, where it is (table frame,
    with its height above the top and its tilt), in the order of ``shapes``."""
    out = []
    top = scene.target_table.height
    for p in shapes:
        s = states.get(p.name)
        if s is None or s.held or s.table != scene.target:
            continue
        x, y, yaw = table_pose(s, scene)
        out.append(replace(p, x=x, y=y, yaw=yaw, on=s.on, z_m=round(s.z - top, 4),
                           tilt_rad=round(s.tilt_rad, 4)))
    return tuple(out)


#: A nudged target keeps a footprint this far from the object it landed on, metres.
CLEAR_GAP_M = 0.004


def clear_of(x: float, y: float, mine: Placement, other: Placement, limit_m: float
             ) -> tuple[float, float] | None:
    """A target near ``(x, y)`` (table frame, metres) where ``mine`` at its yaw keeps
    :data:`CLEAR_GAP_M` from ``other`` as it lies, moved straight away from ``other`` by at
    most ``limit_m``; ``None`` when none is that near (or ``(x, y)`` is ``other``'s centre).
    Where a place came to rest on an object it should not, the next attempt aims beside
    it, as a robot that sees the obstacle would."""
    theirs = footprint(other.x, other.y, other.yaw, other.shape, other.size)
    away = np.array([x - other.x, y - other.y])
    if float(np.hypot(*away)) < 1e-6:
        return None
    away /= np.hypot(*away)
    for d in np.arange(0.0, limit_m + 1e-9, 0.002):
        cx, cy = x + d * float(away[0]), y + d * float(away[1])
        if footprint(cx, cy, mine.yaw, mine.shape, mine.size).distance(theirs) >= CLEAR_GAP_M:
            return round(cx, 4), round(cy, 4)
    return None
