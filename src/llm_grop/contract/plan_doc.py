"""The plan JSON: a task-motion plan a robot stack executes (``POST /v1/plans`` of
``llm-grop serve``), as typed models, a writer and a reader.

It holds what a robot needs, in the contract's frames: the ordered steps with their
navigation goals and paths, standing positions and pick and place poses, each step's
success probability and expected duration; the plan's expected utility and duration; the
arrangement it realises; and the episode's scene (the sensed chairs, where each object
waits). Poses and paths keep full float precision (JSON reads a float back exactly), so
executing a plan read from this JSON gives the same run as executing the plan itself.
"""

from __future__ import annotations

import json
from dataclasses import replace
from typing import Annotated, Any, Literal

from pydantic import ConfigDict, Field

from llm_grop.contract.models import (
    ArrangementDoc,
    Doc,
    Int,
    Name,
    Num,
    PlanDoc,
    RoomPose,
    Seconds,
    Text,
)
from llm_grop.contract.run_json import plan_doc
from llm_grop.contract.serialize import arrangement_doc, arrangement_from_dict, read_doc
from llm_grop.files.scene_file import SceneFile, parse_scene, scene_to_dict
from llm_grop.world.arrangement import Arrangement
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import Plan, Step
from llm_grop.world.scene import Scene

Probability = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]


class PlanStepDoc(Doc):
    """One planned action, in order. ``navigate``: ``goal`` (room frame), the planned
    ``path`` and fallback goals ``alternatives``, best first; ``pick``: ``standing`` and
    ``pose``, the object's start (room frame ``[x, y, 0]``); ``place``: ``standing`` and
    ``pose``, the object's target (table frame ``[x, y, yaw]``)."""

    action: Literal["navigate", "pick", "place"]
    object: Text | None = Field(None, description="the object picked or placed; for "
                                                  "navigate, the object the leg fetches or "
                                                  "delivers")
    goal: RoomPose | None = None
    path: list[tuple[Num, Num]] | None = Field(None, description="room-frame points, metres")
    alternatives: list[RoomPose] | None = None
    standing: RoomPose | None = None
    pose: tuple[Num, Num, Num] | None = None
    duration_s: Seconds = Field(description="expected seconds, nothing failing")
    success_p: Probability = Field(description="the planner's belief that the action "
                                               "succeeds at the first attempt")


class PlanJSON(Doc):
    """The plan JSON: what ``POST /v1/plans`` answers."""

    model_config = ConfigDict(title="llm-grop plan JSON")

    method: Name
    task: Int | None = None
    seed: Int
    request: Text
    feasibility: Name = Field("default", description="the planner's feasibility profile")
    planning_time_s: Seconds = Field(description="wall-clock seconds, LLM calls excluded")
    manip_attempts: Int = Field(description="attempts per pick and per place the executive "
                                            "allows the method")
    plan: PlanDoc = Field(description="the summary the run JSON holds: order, standing "
                                      "positions, expected utility, feasibility and duration")
    steps: list[PlanStepDoc]
    arrangement: ArrangementDoc = Field(description="the arrangement the plan realises, with "
                                                    "how the request was read")
    scene: SceneFile = Field(description="the episode's room: the sensed chairs and where "
                                         "each object waits")


def _pose(p: Pose2D | None) -> tuple[float, float, float] | None:
    return None if p is None else (p.x, p.y, p.theta)


def step_json(s: Step) -> PlanStepDoc:
    """One planned step, at full precision."""
    out: dict[str, Any] = {"action": s.action, "duration_s": s.duration_s,
                           "success_p": min(max(s.success_p, 0.0), 1.0)}
    if s.object is not None:
        out["object"] = s.object
    for key in ("goal", "standing"):
        if getattr(s, key) is not None:
            out[key] = _pose(getattr(s, key))
    if s.path:
        out["path"] = [tuple(p) for p in s.path]
    if s.alternatives:
        out["alternatives"] = [_pose(a) for a in s.alternatives]
    if s.pose is not None:
        out["pose"] = tuple(s.pose)
    return PlanStepDoc(**out)


def plan_json(*, method: str, task: int | None, seed: int, request: str, plan: Plan,
              arrangement: Arrangement, scene: Scene, planning_time_s: float,
              feasibility: str, manip_attempts: int) -> PlanJSON:
    """The plan JSON of ``plan`` for ``arrangement`` in ``scene``."""
    return PlanJSON(method=method, task=task, seed=seed, request=request,
                    feasibility=feasibility, planning_time_s=round(planning_time_s, 4),
                    manip_attempts=manip_attempts, plan=plan_doc(plan),
                    steps=[step_json(s) for s in plan.steps],
                    arrangement=arrangement_doc(replace(arrangement,
                                                        placements=plan.configuration)),
                    scene=SceneFile.model_validate(scene_to_dict(scene)))


def _pose2d(p: tuple[float, float, float] | None) -> Pose2D | None:
    return None if p is None else Pose2D(*p)


def read_plan_json(data: Any, where: str = "plan") -> tuple[PlanJSON, Plan, Arrangement,
                                                             Scene]:
    """The plan JSON ``data`` (as written by :func:`plan_json`, by any version) read back:
    its document, the plan, the arrangement and the scene. The configuration's poses are
    the place steps' exact targets. Raises :class:`~llm_grop.errors.BadInput` naming
    ``where`` and the field."""
    doc = read_doc(PlanJSON, data, where)
    arrangement = arrangement_from_dict(doc.arrangement.to_json(), f"{where}: arrangement")
    steps = tuple(Step(s.action, s.object, _pose2d(s.goal), tuple(map(tuple, s.path or ())),
                       _pose2d(s.standing), s.pose, s.duration_s, s.success_p,
                       tuple(Pose2D(*a) for a in s.alternatives or ()))
                  for s in doc.steps)
    targets = {s.object: s.pose for s in steps if s.action == "place" and s.pose is not None}
    placements = tuple(replace(p, x=targets[p.name][0], y=targets[p.name][1],
                               yaw=targets[p.name][2]) if p.name in targets else p
                       for p in arrangement.placements)
    summary = doc.plan
    plan = Plan(order=tuple(summary.order), steps=steps, configuration=placements,
                configuration_index=summary.configuration_index,
                utility=summary.expected_utility, feasibility=summary.feasibility,
                cost_s=summary.expected_cost_s,
                configurations_considered=summary.configurations,
                fidelity_w_s_per_cm=summary.fidelity.weight_s_per_cm
                if summary.fidelity is not None else 0.0,
                expected_duration_s=summary.expected_duration_s)
    scene = parse_scene(json.dumps(doc.scene.model_dump(mode="json", exclude_unset=True)),
                        f"{where}: scene")
    return doc, plan, replace(arrangement, placements=placements), scene
