"""Picks and places for the executive: the retry, re-grasp and give-up policy of one
object's manipulation (:mod:`llm_grop.execution.executive` documents the policy).

An attempt the arm cannot reach moves the robot to the leg's next standing position; a
released object is judged where it came to rest, re-grasped and placed again while it
stands upright on the table, and given up when it tipped, fell, failed the same way twice
in a row or its attempts ran out.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import Protocol

from llm_grop.execution.judge import clear_of, judged_place, table_pose
from llm_grop.execution.tray import Attempts, take
from llm_grop.world.arrangement import Placement
from llm_grop.world.plan import ObjectState, Reason
from llm_grop.world.scene import Scene

#: A place that fails as the one before it did, its object coming to rest within this
#: distance of where it rested then (metres), is not tried a third time: repeating an
#: action that the world answers the same way only spends time (the hand that knocks a
#: neighbour aside, a spot that something else now fills). Physics repeats itself to a
#: millimetre or two; two random 2D slides land this close about once in 400 pairs.
REPEAT_M = 0.005


class Hands(Attempts, Protocol):
    """What picks and places need of the executive besides :class:`Attempts`: the
    scene, each object's target, the objects in place and disturbed, and its moves."""

    scene: Scene
    targets: Mapping[str, Placement]
    placed: dict[str, ObjectState]
    disturbed: list[str]

    def next_stand(self, name: str) -> bool: ...

    def goal(self, name: str, states: Mapping[str, ObjectState]) -> tuple[float, float]: ...

    def back_to(self, name: str) -> bool: ...

    def replace_disturbed(self) -> None: ...

    def give_up(self, name: str, reason: Reason) -> None: ...

    def _last_reason(self, name: str, default: Reason) -> Reason: ...


def pick(ex: Hands, name: str) -> Reason | None:
    """Pick ``name`` from where it lies, within its pick attempts: ``None`` when it is
    in the hand, else why not (one that tipped or fell is not tried again; one out of
    reach is tried from the leg's next standing position)."""
    return take(ex, name, ex.s.pick, lambda state: state.table is None,
                lambda: ex._left(name, "pick") > 0 and ex.next_stand(name))


def place(ex: Hands, name: str) -> bool:
    """Place the held ``name`` at its target, within its place attempts: re-grasping
    it where it came to rest when it stands upright on the table, giving it up when
    it tipped, fell, failed the same way twice in a row or its attempts ran out."""
    t = ex.targets[name]
    landed_on: str | None = None
    last: tuple[Reason | None, float, float] | None = None
    while ex._left(name, "place") > 0:
        if not ex.s.objects()[name].held:
            # Lost on the way (it slipped from the hand in transit).
            ex.give_up(name, ex._last_reason(name, "fell"))
            return False
        on = _support(ex, t.on)
        attempt = ex._use(name, "place")
        target = ex.goal(name, ex.s.objects()) if on is not None else (t.x, t.y)
        # Aimed beside what it landed on last time, but judged against its target; an
        # object that goes on another keeps aiming at its support's centre.
        x, y = _beside(ex, name, *target, landed_on) \
            if landed_on is not None and on is None else target
        done, state = judged_place(ex.s, ex.scene, name, x, y, t.yaw, on, ex.policy,
                                   target)
        ex.record(replace(done, object=name, attempt=attempt))
        ex.check_placed(name)
        if done.ok:
            ex.placed[name] = state
            return True
        if done.reason is None:
            raise RuntimeError(f"the simulator refused to place {name!r}: {done.note}")
        if state.held:
            # It never left the hand: try again, from elsewhere when out of reach.
            last = None
            if done.reason == "no_ik" and ex._left(name, "place") > 0 \
                    and not ex.next_stand(name):
                break
            continue
        landed_on = state.on if done.reason == "wrong_support" and state.on != on \
            else None
        again = last is not None and last[0] == done.reason \
            and math.hypot(state.x - last[1], state.y - last[2]) < REPEAT_M
        last = (done.reason, state.x, state.y)
        if (done.reason in ("tipped", "fell") or again or state.table != ex.scene.target
                or ex._left(name, "place") <= 0):
            ex.give_up(name, done.reason)
            return False
        if ex.disturbed:
            # Put back what this place moved (its support, say) with the hand empty.
            ex.replace_disturbed()
            if not ex.back_to(name):
                ex.give_up(name, done.reason)
                return False
        if pick(ex, name) is not None:
            ex.give_up(name, done.reason)
            return False
    ex.give_up(name, ex._last_reason(name, "contact"))
    return False


def _support(ex: Hands, on: str | None) -> str | None:
    """``on`` when that object lies upright on the target table, else ``None``: an
    object whose support is missing or tipped goes on the table."""
    state = ex.s.objects().get(on or "")
    if state is None or state.held or state.table != ex.scene.target \
            or state.tilt_rad > ex.policy.max_tilt_rad:
        return None
    return on


def _beside(ex: Hands, name: str, x: float, y: float, other: str) -> tuple[float, float]:
    """``(x, y)`` (table frame) moved clear of ``other`` as it lies now, by at most
    0.8 of the place tolerance; unchanged when that is not enough."""
    state, planned = ex.s.objects().get(other), ex.targets.get(other)
    if state is None or planned is None or state.table != ex.scene.target:
        return x, y
    ox, oy, oyaw = table_pose(state, ex.scene)
    moved = clear_of(x, y, ex.targets[name], replace(planned, x=ox, y=oy, yaw=oyaw),
                     0.8 * ex.policy.max_offset_m)
    return moved if moved is not None else (x, y)
