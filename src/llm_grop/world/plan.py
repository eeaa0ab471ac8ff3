"""Task-motion plans and what happened when one was executed (paper §III-C)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from llm_grop.world.arrangement import Arrangement, Placement
from llm_grop.world.fidelity import Considered, Fidelity
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.scene import Scene

Action = Literal["navigate", "pick", "place"]
Point = tuple[float, float]
#: Why an attempt failed, or why an object ended unplaced: one closed list for every
#: simulator. ``blocked``: no path, or the base was held back short of its goal;
#: ``contact``: the robot (or what it holds) touched furniture; ``no_ik``: the arm cannot
#: reach the pose from where the base stands; ``grasp_missed``: the gripper closed on
#: nothing; after release, the object ``tipped`` over, ``slid`` away from its target,
#: ``fell`` to the floor, or came to rest on the ``wrong_support``; ``disturbed``: a
#: later action moved an object that was in place out of tolerance.
Reason = Literal["blocked", "contact", "no_ik", "grasp_missed", "tipped", "slid", "fell",
                 "wrong_support", "disturbed"]
REASONS: tuple[Reason, ...] = ("blocked", "contact", "no_ik", "grasp_missed", "tipped",
                               "slid", "fell", "wrong_support", "disturbed")


@dataclass(frozen=True)
class StandingPose:
    """A candidate place for the robot's base next to a table.

    ``pose`` is in the room frame, facing the table; ``clearance_m`` is the free distance
    from the base's footprint to the nearest obstacle (tables, walls, sensed chairs), metres.
    """

    pose: Pose2D
    clearance_m: float
    table: str = ""


@dataclass(frozen=True)
class Step:
    """One planned action.

    Attributes:
        action: ``navigate``, ``pick`` or ``place``.
        object: the object picked or placed; for ``navigate``, the object this leg
            fetches or delivers.
        goal: the navigation goal (room frame), for ``navigate``.
        path: the planned collision-free path (room-frame points, metres), for ``navigate``.
        standing: where the base stands, for ``pick`` and ``place`` (room frame).
        pose: the object's target ``(x, y, yaw)`` in the table frame, for ``place``;
            its start ``(x, y, 0)`` in the room frame, for ``pick``.
        duration_s: the expected duration without failures, seconds.
        success_p: the feasibility model's success probability of this action.
        alternatives: fallback navigation goals, best first, for ``navigate``.
    """

    action: Action
    object: str | None = None
    goal: Pose2D | None = None
    path: tuple[Point, ...] = ()
    standing: Pose2D | None = None
    pose: tuple[float, float, float] | None = None
    duration_s: float = 0.0
    success_p: float = 1.0
    alternatives: tuple[Pose2D, ...] = ()


@dataclass(frozen=True)
class Plan:
    """A task-motion plan for one configuration.

    Attributes:
        order: objects in the order they are placed.
        steps: the actions.
        configuration: the placements the plan realises (table frame).
        configuration_index: which of the M configurations it is (0-based).
        utility: expected utility, ``w * feasibility - cost`` summed over objects.
        feasibility: the probability that every action succeeds first time.
        cost_s: expected duration without failures (navigation and manipulation), seconds.
        configurations_considered: how many configurations were planned for (M).
        fidelity: how faithfully the chosen configuration keeps the stated geometry.
        considered: every configuration GROP evaluated, with its utility, fidelity and
            score (utility minus the fidelity penalty).
        fidelity_w_s_per_cm: the fidelity weight, seconds per centimetre, of the choice.
        expected_duration_s: expected seconds of execution, expected retries included
            (``None``: the steps' durations, nothing failing).
    """

    order: tuple[str, ...]
    steps: tuple[Step, ...]
    configuration: tuple[Placement, ...]
    configuration_index: int
    utility: float
    feasibility: float
    cost_s: float
    configurations_considered: int = 1
    fidelity: Fidelity = Fidelity()
    considered: tuple[Considered, ...] = ()
    fidelity_w_s_per_cm: float = 0.0
    expected_duration_s: float | None = None


@dataclass(frozen=True)
class ExecutedStep:
    """One action as the simulator executed it (an attempt; failures are kept).

    ``path`` is the driven path (room frame); ``pose`` for ``place`` is where the object
    really landed, table frame; ``attempt`` counts from 1; ``note`` says why it failed in
    words and ``reason`` as one of :data:`REASONS` (``None`` when it succeeded, or for an
    action refused before any attempt, such as a pick while the hand is full). A
    ``navigate`` step records where the base ended against its goal: ``arrival_error_m``
    (metres) and ``arrival_yaw_error_rad`` (radians, absolute).
    """

    action: Action
    ok: bool
    duration_s: float
    object: str | None = None
    goal: Pose2D | None = None
    path: tuple[Point, ...] = ()
    standing: Pose2D | None = None
    pose: tuple[float, float, float] | None = None
    attempt: int = 1
    note: str = ""
    reason: Reason | None = None
    arrival_error_m: float | None = None
    arrival_yaw_error_rad: float | None = None
    tray: bool = False


@dataclass(frozen=True)
class ObjectState:
    """Where an object physically is: its bottom centre ``(x, y, z)`` in the room frame
    (metres), ``yaw`` about the vertical and ``tilt_rad`` of its up axis from the vertical
    (radians); ``table`` is the table it lies on or above (``None``: the floor, or the
    hand), ``on`` the object it rests on (``None``: none, read from contact in physics),
    ``held`` whether the hand holds it, ``tray`` whether it rides on the robot's tray."""

    name: str
    x: float
    y: float
    z: float
    yaw: float
    tilt_rad: float = 0.0
    table: str | None = None
    on: str | None = None
    held: bool = False
    tray: bool = False


@dataclass(frozen=True)
class Execution:
    """What happened when a plan was executed.

    ``final`` holds every object resting on the target table where it really is (table
    frame, with its height and tilt); ``unplaced`` the requested objects that did not end
    upright on their intended support within tolerance of their target, and
    ``unplaced_reasons`` why, one of :data:`REASONS` per object;
    ``execution_time_s`` the simulated seconds; ``trips`` the objects carried on each
    trip, in the order they were picked (a trip of several rides on the robot's tray).
    """

    steps: tuple[ExecutedStep, ...]
    final: tuple[Placement, ...]
    unplaced: tuple[str, ...]
    execution_time_s: float
    robot_end: Pose2D
    unplaced_reasons: tuple[tuple[str, Reason], ...] = ()
    trips: tuple[tuple[str, ...], ...] = ()

    @property
    def success(self) -> bool:
        """Whether every requested object ended upright on its intended support, within
        tolerance of its target."""
        return not self.unplaced

    @property
    def failures(self) -> int:
        """How many actions failed."""
        return sum(not s.ok for s in self.steps)


@dataclass(frozen=True)
class RunResult:
    """One episode (the contract's run JSON): the planned arrangement, the plan, its
    execution, the final arrangement, planning time in seconds (LLM calls excluded), the
    scene with the chairs that were sensed, the name of the simulator that executed
    the plan, and the planner's feasibility profile."""

    method: str
    task: int | None
    seed: int
    request: str
    planned: Arrangement
    plan: Plan
    execution: Execution
    final: Arrangement
    planning_time_s: float
    scene: Scene
    simulator: str
    feasibility: str = "default"

    @property
    def success(self) -> bool:
        """Whether every requested object ended upright on its intended support, within
        tolerance of its target."""
        return self.execution.success
