"""Running a plan on a session: the one retry, fallback, re-grasp and give-up policy.

* **Navigation.** Each goal gets ``nav_attempts`` attempts: the first follows the plan's
  path, later ones a path the robot plans from where it stopped. When a goal has no path,
  or its attempts run out, the plan's fallback goals are tried in turn. When every goal
  fails, the object of the leg is given up.
* **Picks and places** (:mod:`llm_grop.execution.manipulation`). Each object gets
  ``manip_attempts`` picks and as many places, re-grasps and re-places included. An
  attempt the arm cannot reach (``no_ik``) is followed by a move to the leg's next
  standing position: its fallbacks, then a fresh arrival at the planned one.
* **Success after release.** A released object is judged where it came to rest
  (:func:`~llm_grop.execution.judge.judge`). One that slid or landed on the wrong support
  but stands upright on the table is re-grasped from where it lies and placed again;
  one that tipped or fell is given up. An object that goes on another is aimed at its
  support where the support lies, and one that came to rest on an object it should not
  is aimed beside that object next time, within the place tolerance. A place that fails
  the same way twice in a row, the object resting where it rested before, is given up.
* **Disturbance.** After every attempt the objects already in place are judged again; one
  that a later action moved out of tolerance is reported ``disturbed`` and, while its
  attempts remain and nothing rests on it, re-placed from its own standing position.
* **Giving up.** The object in the hand is put down away from the table (on the floor),
  and the plan goes on with the next object. Before that, a :class:`Rescue` the executive
  is given may name another spot for an object in the hand, or for one a place left
  upright on the target table (it slid, or came to rest on another object, the same way
  twice); the object is picked up again if it must be, driven to and placed there.
* **Trips** (:mod:`llm_grop.execution.trips`). Each of the plan's trips picks its objects
  in turn, then places them in turn. A trip of one carries its object in the hand; a trip
  of several carries them on the robot's tray: each is loaded after its pick and unloaded
  before its place (:mod:`llm_grop.execution.tray`). A trip whose objects do not all fit
  the tray together, or that carries more than the robot's capacity, is cut into
  consecutive trips that do; their legs are then driven along paths the robot plans
  itself.

The result is read from the session at the end: ``final`` lists every object on the
target table as it is, and an object is placed exactly when it is in place there.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import cast

import numpy as np

from llm_grop.execution.judge import (
    final_placements,
    judge,
    table_pose,
)
from llm_grop.execution.manipulation import pick, place
from llm_grop.execution.policy import BASELINE_MANIP_ATTEMPTS, ExecutionPolicy
from llm_grop.execution.rescue import Rescue
from llm_grop.execution.tray import load, unload
from llm_grop.execution.trips import Carry, Trip, plan_trips, split_trip
from llm_grop.recording.stream import BodyPose, EpisodeObserver
from llm_grop.simulation.base import ObservedSession, PathPlanner, Session, Simulator
from llm_grop.world.arrangement import Item
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, Execution, ObjectState, Plan, Point, Reason, Step
from llm_grop.world.scene import Scene

log = logging.getLogger(__name__)

#: Why a place may leave an object it gives up upright on the target table, where it can be
#: picked up again for a spot the rescue names (one that tipped or fell cannot).
_LIFTABLE: frozenset[Reason] = frozenset({"slid", "wrong_support"})

def execute(simulator: Simulator, plan: Plan, scene: Scene, items: Sequence[Item],
            rng: np.random.Generator, *, replan: PathPlanner,
            policy: ExecutionPolicy | None = None,
            observer: EpisodeObserver | None = None,
            rescue: Rescue | None = None) -> Execution:
    """Run ``plan`` for ``items`` in a new episode of ``simulator`` in ``scene`` (its chairs
    are the true ones), the simulator's randomness from ``rng``; ``replan`` is the robot's
    own path planner. ``observer`` hears every attempt and where everything is after it,
    and, while attempts run, what the simulator declares it reports (its ``streams``).
    ``rescue`` is asked for another spot before an object still in the hand is given up."""
    session = simulator.session(scene, items, rng, replan=replan)
    if observer is not None and simulator.streams:
        # Declared by the class: its sessions take an observer.
        cast(ObservedSession, session).watch(observer)
    return execute_plan(plan, session, scene, policy, observer, rescue)


def execute_plan(plan: Plan, session: Session, scene: Scene,
                 policy: ExecutionPolicy | None = None,
                 observer: EpisodeObserver | None = None,
                 rescue: Rescue | None = None) -> Execution:
    """Run ``plan`` on ``session`` (an episode in ``scene``) under ``policy`` and report
    what physically happened (each attempt also to ``observer``); the session is closed
    at the end. ``rescue``: see :func:`execute`."""
    try:
        return _Executive(plan, session, scene, policy or ExecutionPolicy(), observer,
                          rescue).run()
    finally:
        session.close()


class _Executive:
    """The state of one execution: every attempt so far, the objects in place as they
    settled, and the attempts each object has left."""

    def __init__(self, plan: Plan, session: Session, scene: Scene,
                 policy: ExecutionPolicy, observer: EpisodeObserver | None = None,
                 rescue: Rescue | None = None) -> None:
        self.plan, self.s, self.scene, self.observer = plan, session, scene, observer
        self.rescue = rescue
        self.policy = policy.for_method(BASELINE_MANIP_ATTEMPTS)
        self.targets = {p.name: p for p in plan.configuration}
        self.steps: list[ExecutedStep] = []
        #: Objects in place, as they were when last judged in place.
        self.placed: dict[str, ObjectState] = {}
        #: Objects given up, and why.
        self.given_up: dict[str, Reason] = {}
        #: Attempts used per ``(object, action)``.
        self.used: dict[tuple[str, str], int] = {}
        #: Each object's place leg, for re-placing it after a disturbance.
        self.place_legs: dict[str, Step] = {}
        self.leg: Step | None = None
        self.turn = 0
        self.disturbed: list[str] = []
        #: The objects of each trip as carried.
        self.trips: list[tuple[str, ...]] = []

    # -- the plan ---------------------------------------------------------------------
    def run(self) -> Execution:
        self.report()
        trips = plan_trips(self.plan.steps)
        if trips is None:
            raise ValueError("the plan's steps are not trips: each object's pick, then its "
                             "place, each after the leg that leads there")
        for trip in trips:
            parts = split_trip(trip, self.scene.robot.capacity, self.s.fits_tray) \
                if len(trip.carries) > 1 else (trip,)
            for k, part in enumerate(parts):
                # A trip cut in parts drives its later legs along paths of its own.
                self.carry(part, planned_paths=len(parts) == 1 or k == 0)
        if self.s.held is None:
            self.replace_disturbed()
        return self.result()

    def _between(self, name: str, placed: bool) -> None:
        """Put back disturbed objects between deliveries, with the hand empty: after a
        place, or once ``name`` was given up."""
        if (placed or name in self.given_up) and self.s.held is None:
            self.replace_disturbed()

    def carry(self, trip: Trip, *, planned_paths: bool) -> None:
        """Carry out ``trip``: fetch each object (onto the tray when it carries several),
        then deliver each; the first leg follows its planned path, the later ones too
        when ``planned_paths``."""
        tray = len(trip.carries) > 1
        self.trips.append(trip.objects)
        first = True
        for c in trip.carries:
            if c.object in self.given_up:
                continue
            self.fetch(c, tray, planned_paths or first)
            first = False
        for c in trip.carries:
            if c.object in self.given_up:
                continue
            self.deliver(c, planned_paths or first)
            first = False

    def fetch(self, c: Carry, tray: bool, planned_path: bool) -> None:
        """Drive to ``c``'s pickup, pick it, and load it onto the tray when ``tray``."""
        name = c.object
        if c.pickup_leg is not None:
            leg = c.pickup_leg
            if not self.go_leg(leg, leg.path if planned_path else ()):
                self.give_up(name, self._last_reason(name, "blocked"))
            self._between(name, False)
            if name in self.given_up:
                return
        why = pick(self, name)
        if why is not None:
            self.give_up(name, why)
        elif tray:
            why = load(self, name)
            if why is not None:
                self.give_up(name, why)
        self._between(name, False)

    def deliver(self, c: Carry, planned_path: bool) -> None:
        """Drive to where ``c`` is placed, unload it from the tray if it rides there, and
        place it."""
        name = c.object
        if c.place_leg is not None:
            leg = c.place_leg
            self.place_legs[name] = leg
            if not self.go_leg(leg, leg.path if planned_path else ()):
                self.give_up(name, self._last_reason(name, "blocked"))
            self._between(name, False)
            if name in self.given_up or name in self.placed:
                return  # given up, or placed elsewhere by a rescue
        if self.s.objects()[name].tray:
            why = unload(self, name)
            if why is not None:
                self.give_up(name, why)
                self._between(name, False)
                return
        place(self, name)
        self._between(name, True)

    def result(self) -> Execution:
        states = self.s.objects()
        final = final_placements(states, self.plan.configuration, self.scene)
        unplaced: list[str] = []
        reasons: list[tuple[str, Reason]] = []
        for name in self.plan.order:
            why = judge(states[name], self.goal(name, states), self.targets[name].on, self.scene,
                        self.policy)
            if why is not None:
                unplaced.append(name)
                reasons.append((name, self.given_up.get(name, why)))
        return Execution(tuple(self.steps), final, tuple(unplaced),
                         round(sum(s.duration_s for s in self.steps), 6), self.s.robot_pose(),
                         tuple(reasons), tuple(self.trips))

    # -- navigation -------------------------------------------------------------------
    def go(self, goals: Sequence[Pose2D], name: str, path: Sequence[Point] = ()
           ) -> int | None:
        """Drive to the first of ``goals`` that can be reached within the attempts (the
        first attempt at the first goal follows ``path``); the index of the goal reached,
        ``None`` when none was."""
        for k, goal in enumerate(goals):
            for attempt in range(1, self.policy.nav_attempts + 1):
                done = self.s.navigate(goal, path if k == 0 and attempt == 1 else ())
                self.record(replace(done, object=name or None, goal=goal, attempt=attempt))
                self.check_placed(name)
                if done.ok:
                    return k
                if done.reason == "fell":
                    return None  # what it carried is lost: nothing left to deliver
                if done.reason == "blocked" and not done.path:
                    break  # no path to this goal: the next one
        return None

    def go_leg(self, leg: Step, path: Sequence[Point] = ()) -> bool:
        """Drive to ``leg``'s goal or one of its fallbacks, and make it the leg whose
        standing positions an unreachable attempt moves between."""
        assert leg.goal is not None
        reached = self.go((leg.goal, *leg.alternatives), leg.object or "", path)
        # Standing positions cycle fallbacks first, then the planned goal: start after the
        # one reached.
        self.leg, self.turn = leg, 0 if reached is None else reached
        return reached is not None

    def next_stand(self, name: str) -> bool:
        """Move to the current leg's next standing position (its fallbacks, then a fresh
        arrival at the planned one), after an attempt the arm could not reach."""
        leg = self.leg
        if leg is None or leg.goal is None:
            return False
        stands = (*leg.alternatives, leg.goal)
        for _ in range(len(stands)):
            goal = stands[self.turn % len(stands)]
            self.turn += 1
            if self.go((goal,), name) is not None:
                return True
        return False

    # -- manipulation -----------------------------------------------------------------
    def _left(self, name: str, action: str) -> int:
        assert self.policy.manip_attempts is not None
        return self.policy.manip_attempts - self.used.get((name, action), 0)

    def _use(self, name: str, action: str) -> int:
        n = self.used.get((name, action), 0) + 1
        self.used[(name, action)] = n
        return n

    def goal(self, name: str, states: Mapping[str, ObjectState]) -> tuple[float, float]:
        """Where ``name`` belongs, table frame (metres), with the objects as ``states``
        says: its target, translated with its support when it goes on an object that lies
        on the table elsewhere than planned, as a robot aims a lid at the mug it sees."""
        t = self.targets[name]
        support = self.targets.get(t.on or "")
        state = states.get(t.on or "")
        if support is None or state is None or state.held \
                or state.table != self.scene.target:
            return t.x, t.y
        x, y, _ = table_pose(state, self.scene)
        return t.x + x - support.x, t.y + y - support.y

    def back_to(self, name: str) -> bool:
        """Drive back to where the plan places ``name``."""
        leg = self.place_legs.get(name)
        return leg is not None and leg.goal is not None and self.go_leg(leg)

    # -- disturbance ------------------------------------------------------------------
    def check_placed(self, acting: str) -> None:
        """Judge the objects in place again after an attempt on ``acting``; report those
        it moved out of tolerance."""
        if not self.placed:
            return
        states = self.s.objects()
        for name in list(self.placed):
            if name == acting:
                continue
            why = judge(states[name], self.goal(name, states), self.placed[name].on, self.scene,
                        self.policy)
            if why is None:
                continue
            del self.placed[name]
            self.disturbed.append(name)
            self.record(ExecutedStep(
                "place", False, 0.0, name, pose=table_pose(states[name], self.scene),
                attempt=max(1, self.used.get((name, "place"), 1)), reason="disturbed",
                note=f"moved while handling {acting!r}: {why}"))

    def replace_disturbed(self) -> None:
        """Put back the objects a later action moved, while their attempts remain."""
        while self.disturbed:
            name = self.disturbed.pop(0)
            if name in self.placed or name in self.given_up:
                continue
            states = self.s.objects()
            state = states[name]
            carrying = any(s.on == name for s in states.values())
            if (carrying or state.table is None or state.tilt_rad > self.policy.max_tilt_rad
                    or min(self._left(name, "pick"), self._left(name, "place")) <= 0
                    or not self.back_to(name)):
                self.given_up[name] = "disturbed"
            elif pick(self, name) is not None:
                self.give_up(name, "disturbed")
            else:
                place(self, name)

    # -- bookkeeping ------------------------------------------------------------------
    def give_up(self, name: str, reason: Reason) -> None:
        """Stop working on ``name``: put it down away from the table if it is in hand;
        unless, while the hand holds it, the rescue gives it another spot, where it is
        placed instead."""
        if self._rescued(name, reason):
            return
        self.given_up[name] = reason
        if self.s.objects()[name].held:
            spent = self.s.release(name)
            mine = [k for k, s in enumerate(self.steps)
                    if s.object == name and s.reason != "disturbed"]
            if mine and spent > 0:
                last = self.steps[mine[-1]]
                self.steps[mine[-1]] = replace(last,
                                               duration_s=round(last.duration_s + spent, 6))
            self.check_placed(name)
        log.debug("gave up %s: %s", name, reason)

    def _rescued(self, name: str, reason: Reason) -> bool:
        """Whether the rescue gave ``name`` another spot, while the hand holds it or a
        place left it upright on the target table; it is then picked up again if it must
        be, driven to and placed there, with the attempts of a fresh target (a failure
        there is given up, or rescued again, in turn)."""
        state = self.s.objects()[name]
        if self.rescue is None or state.tray:
            return False
        lying = not state.held
        if lying and (reason not in _LIFTABLE or state.table != self.scene.target
                      or state.tilt_rad > self.policy.max_tilt_rad
                      or any(s.on == name for s in self.s.objects().values())):
            return False
        leg = self.place_legs.get(name)
        tried = () if leg is None or leg.goal is None else (leg.goal, *leg.alternatives)
        spot = self.rescue(name, reason, self.s.objects(), self.s.robot_pose(), tried)
        if spot is None:
            return False
        log.debug("rescued %s (%s): a new target at %+.2f, %+.2f", name, reason,
                  spot.target.x, spot.target.y)
        self.targets[name] = spot.target
        self.used.pop((name, "place"), None)
        self.place_legs[name] = spot.leg
        if lying:
            self.used.pop((name, "pick"), None)
            why = pick(self, name)
            if why is not None:
                self.given_up[name] = why
                return True
        if self.go_leg(spot.leg):
            place(self, name)
        else:
            self.give_up(name, self._last_reason(name, "blocked"))
        return True

    def _last_reason(self, name: str, default: Reason) -> Reason:
        """Why the last failed attempt on ``name`` failed (``default``: none says)."""
        for s in reversed(self.steps):
            if s.object == name and not s.ok and s.reason is not None:
                return s.reason
        return default

    def record(self, step: ExecutedStep) -> None:
        log.debug("%s %s: %s (%.1f s)", step.action, step.object or "",
                  "ok" if step.ok else f"failed, {step.reason}: {step.note}", step.duration_s)
        self.steps.append(step)
        if self.observer is not None:
            self.observer.step(self.s.time_s, step)
            self.report()

    def report(self) -> None:
        """Tell the observer where the base and every object are now."""
        if self.observer is None:
            return
        t = self.s.time_s
        self.observer.base(t, self.s.robot_pose())
        self.observer.bodies(t, [BodyPose.of_state(o) for o in self.s.objects().values()])

