"""Loading objects onto the robot's tray and unloading them, for the executive.

A load is a place onto the tray, judged as a place is: the object must come to rest on
the tray, upright and on the tray itself (not on another object). Where on the tray it
lies does not matter (it rides wherever it stands, and the arm unloads it from there). A
load that fails before the hand lets go (``contact``) is tried again, once: the arm
moves to the tray along the same way each time, so a third try would meet the same
furniture (the MuJoCo session's load has by then tried every free slot that fits the
object, each taking the elbow another way). One the arm cannot reach (``no_ik``), or
that left the object tipped, fallen or on another, gives the object up where it lies.
An unload is a pick from the tray, tried within the object's attempts; an object no
longer on the tray (it fell in transit) or lying on its side is given up.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Protocol

from llm_grop.execution.policy import ExecutionPolicy
from llm_grop.simulation.base import Session
from llm_grop.world.plan import ExecutedStep, ObjectState, Reason


class Attempts(Protocol):
    """What loading and unloading need of the executive: its session and policy, each
    object's attempts, and the record of every attempt."""

    s: Session
    policy: ExecutionPolicy

    def _left(self, name: str, action: str) -> int: ...

    def _use(self, name: str, action: str) -> int: ...

    def record(self, step: ExecutedStep) -> None: ...

    def check_placed(self, acting: str) -> None: ...


def judge_load(state: ObjectState, policy: ExecutionPolicy) -> Reason | None:
    """Why ``state`` is not riding the tray as loaded, or ``None`` when it is."""
    if state.held:
        return "contact"
    if not state.tray:
        return "fell"
    if state.tilt_rad > policy.max_tilt_rad:
        return "tipped"
    if state.on is not None:
        return "wrong_support"
    return None


def load_words(why: Reason, state: ObjectState) -> str:
    """One line saying how a loaded object is out of place."""
    if why == "tipped":
        return f"it tipped over on the tray ({state.tilt_rad:.2f} rad from upright)"
    if why == "fell":
        return "it fell off the tray"
    return f"it came to rest on the {state.on}, not on the tray"


def judged_load(done: ExecutedStep, state: ObjectState, policy: ExecutionPolicy
                ) -> ExecutedStep:
    """``done``, a load that let go, failed with the reason when ``state`` is not riding
    the tray as loaded."""
    if not done.ok:
        return done
    why = judge_load(state, policy)
    return done if why is None else replace(done, ok=False, reason=why,
                                            note=load_words(why, state))


def load(ex: Attempts, name: str) -> Reason | None:
    """Load the held ``name`` onto the tray, within its place attempts: ``None`` when
    it rides there, else why not."""
    why: Reason = "contact"
    last: Reason | None = None
    while ex._left(name, "place") > 0:
        attempt = ex._use(name, "place")
        done = ex.s.load(name)
        if not done.ok and done.reason is None:
            # No free slot fits it (something given up on the way holds one).
            ex.record(replace(done, object=name, attempt=attempt))
            return "blocked"
        state = ex.s.objects()[name]
        done = judged_load(done, state, ex.policy)
        ex.record(replace(done, object=name, attempt=attempt))
        ex.check_placed(name)
        if done.ok:
            return None
        assert done.reason is not None
        why = done.reason
        if not state.held or why == "no_ik" or (why == last):
            return why
        last = why
    return why


def take(ex: Attempts, name: str, grasp: Callable[[str], ExecutedStep],
         lost: Callable[[ObjectState], bool], elsewhere: Callable[[], bool]) -> Reason | None:
    """Grasp ``name`` with ``grasp`` (a pick from where it lies, an unload from the tray)
    within its pick attempts: ``None`` when it is in the hand, else why not. An object
    that is ``lost`` (no longer where it should lie) fell, one on its side tipped; after
    an attempt the arm could not reach, it goes on only when ``elsewhere()`` moved the
    robot to somewhere else to try from."""
    why: Reason = "grasp_missed"
    while ex._left(name, "pick") > 0:
        state = ex.s.objects()[name]
        if lost(state):
            return "fell"
        if state.tilt_rad > ex.policy.max_tilt_rad:
            return "tipped"
        attempt = ex._use(name, "pick")
        done = grasp(name)
        ex.record(replace(done, object=name, attempt=attempt))
        ex.check_placed(name)
        if done.ok:
            return None
        if done.reason is None:
            raise RuntimeError(f"the simulator refused to grasp {name!r}: {done.note}")
        why = done.reason
        if why == "no_ik" and not elsewhere():
            return why
    return why


def unload(ex: Attempts, name: str) -> Reason | None:
    """Pick ``name`` from the tray, within its pick attempts: ``None`` when it is in
    the hand, else why not."""
    return take(ex, name, ex.s.unload, lambda state: not state.tray, lambda: False)
