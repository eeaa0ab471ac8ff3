"""A session whose primitives return scripted outcomes, to check the executive alone.

Objects start on the counter; a picked object rides in the hand; a place lets go at the
target unless its scripted outcome says otherwise. Every call is logged, so a test can
check the exact path the executive's policy took.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, ObjectState, Point
from llm_grop.world.scene import Scene

#: Simulated seconds of each scripted primitive.
SECONDS = {"navigate": 10.0, "pick": 8.0, "place": 8.0, "no_ik": 2.0, "release": 3.0}


@dataclass
class ScriptedSession:
    """Outcomes per action, consumed in order: ``"ok"``, or a reason (``navigate`` may also
    be ``dropped``: the held object falls to the floor on the way). For ``place``:
    ``contact`` and ``no_ik`` keep the object in the hand; ``slid``, ``tipped`` and
    ``fell`` let go and leave it 5 cm off, on its side, or on the floor; ``on:NAME`` at
    its target, resting on ``NAME``. ``hooks`` run
    after the call with that index (0-based) and may move objects."""

    scene: Scene
    names: Sequence[str]
    script: dict[str, list[str]] = field(default_factory=dict)
    hooks: dict[int, Callable[[ScriptedSession], None]] = field(default_factory=dict)
    calls: list[tuple[str, str]] = field(default_factory=list)
    states: dict[str, ObjectState] = field(default_factory=dict)
    pose: Pose2D = Pose2D(1.5, 0.6, 0.0)
    clock_s: float = 0.0
    hand: str | None = None
    closed: bool = False

    def __post_init__(self) -> None:
        for k, name in enumerate(self.names):
            self.states[name] = ObjectState(name, 0.45, 1.6 + 0.2 * k, 0.75, 0.0,
                                            table="counter")

    @property
    def time_s(self) -> float:
        return self.clock_s

    @property
    def held(self) -> str | None:
        return self.hand

    def robot_pose(self) -> Pose2D:
        return self.pose

    def objects(self) -> dict[str, ObjectState]:
        out = dict(self.states)
        if self.hand is not None:
            out[self.hand] = ObjectState(self.hand, self.pose.x, self.pose.y, 1.1, 0.0,
                                         held=True)
        return out

    def close(self) -> None:
        self.closed = True

    def _next(self, action: str, what: str) -> str:
        self.calls.append((action, what))
        queue = self.script.get(action, [])
        return queue.pop(0) if queue else "ok"

    def _done(self, step: ExecutedStep) -> ExecutedStep:
        self.clock_s += step.duration_s
        hook = self.hooks.pop(len(self.calls) - 1, None)
        if hook is not None:
            hook(self)
        return step

    def navigate(self, goal: Pose2D, path: Sequence[Point] = ()) -> ExecutedStep:
        outcome = self._next("navigate", f"{goal.x:.2f},{goal.y:.2f}" + (" path" if path
                                                                           else ""))
        if outcome == "ok":
            self.pose = goal
            return self._done(ExecutedStep("navigate", True, SECONDS["navigate"], goal=goal,
                                           path=((0.0, 0.0), (goal.x, goal.y))))
        if outcome == "blocked":
            return self._done(ExecutedStep("navigate", False, 0.0, goal=goal, note="no path",
                                           reason="blocked"))
        if outcome == "dropped" and self.hand is not None:
            # The held object slips from the hand on the way and lands on the floor.
            name, self.hand, self.pose = self.hand, None, goal
            self.states[name] = ObjectState(name, goal.x, goal.y, 0.0, 0.0)
            return self._done(ExecutedStep("navigate", False, SECONDS["navigate"], goal=goal,
                                           path=((0.0, 0.0), (goal.x, goal.y)),
                                           reason="fell", note=f"dropped {name!r} in transit"))
        return self._done(ExecutedStep("navigate", False, SECONDS["navigate"] / 2, goal=goal,
                                       path=((0.0, 0.0), (1.0, 1.0)), reason="contact",
                                       note="bumped"))

    def pick(self, name: str) -> ExecutedStep:
        outcome = self._next("pick", name)
        if self.hand is not None:
            return self._done(ExecutedStep("pick", False, 0.0, name, note="hand full"))
        if outcome == "ok":
            self.hand = name
            del self.states[name]
            return self._done(ExecutedStep("pick", True, SECONDS["pick"], name))
        seconds = SECONDS["no_ik" if outcome == "no_ik" else "pick"]
        return self._done(ExecutedStep("pick", False, seconds, name, reason=outcome,  # type: ignore[arg-type]
                                       note=outcome))

    def place(self, name: str, x: float, y: float, yaw: float, on: str | None = None
              ) -> ExecutedStep:
        outcome = self._next("place", name)
        if outcome in ("contact", "no_ik"):
            seconds = SECONDS["no_ik" if outcome == "no_ik" else "place"]
            return self._done(ExecutedStep("place", False, seconds, name, reason=outcome,  # type: ignore[arg-type]
                                           note=outcome))
        q = self.scene.table_to_room(x, y, yaw)
        top = self.scene.target_table.height
        target = self.scene.target
        self.hand = None
        if outcome == "ok":
            z = top + (0.02 if on else 0.0)
            self.states[name] = ObjectState(name, q.x, q.y, z, q.theta, 0.0, target, on)
        elif outcome.startswith("on:"):
            # It comes to rest at the target, but on top of another object.
            self.states[name] = ObjectState(name, q.x, q.y, top + 0.01, q.theta, 0.0, target,
                                            outcome[3:])
        elif outcome == "slid":
            self.states[name] = ObjectState(name, q.x + 0.05, q.y, top, q.theta, 0.0, target)
        elif outcome == "tipped":
            self.states[name] = ObjectState(name, q.x, q.y, top, q.theta, math.pi / 2, target)
        else:
            self.states[name] = ObjectState(name, q.x, q.y - 0.6, 0.0, q.theta, math.pi / 2)
        return self._done(ExecutedStep("place", True, SECONDS["place"], name))

    def release(self, name: str) -> float:
        self.calls.append(("release", name))
        if self.hand == name:
            self.states[self.hand] = ObjectState(self.hand, self.pose.x, self.pose.y, 0.0,
                                                 0.0, math.pi / 2)
            self.hand = None
        self.clock_s += SECONDS["release"]
        return SECONDS["release"]

    def move(self, name: str, dx: float, dy: float = 0.0, tilt_rad: float = 0.0) -> None:
        """Push ``name`` by ``(dx, dy)`` metres (room frame), tilting it."""
        s = self.states[name]
        self.states[name] = ObjectState(name, s.x + dx, s.y + dy, s.z, s.yaw,
                                        s.tilt_rad + tilt_rad, s.table, s.on)
