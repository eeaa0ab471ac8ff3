"""The contract's run JSON (``llm-grop run --json``), built from a :class:`RunResult` as a
:class:`~llm_grop.contract.models.RunDoc`.

Besides the contract's fields it holds the planned arrangement, the plan's expected
utility, feasibility and cost, the failures, the simulator, and the scene with the sensed
chairs. For the same seed and inputs it is identical except for measured wall times
(``planning_time_s`` and the LLM calls' ``latency_s``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from llm_grop.contract.models import (
    ConsideredDoc,
    FidelityDoc,
    GapDoc,
    PlanDoc,
    PlanFidelityDoc,
    RunDoc,
    StandingDoc,
    StepDoc,
)
from llm_grop.contract.serialize import arrangement_doc
from llm_grop.files.jsonio import rounded
from llm_grop.files.scene_file import SceneFile, scene_to_dict
from llm_grop.world.fidelity import Considered, Fidelity
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.plan import ExecutedStep, Plan, RunResult


def pose_list(p: Pose2D) -> tuple[float, float, float]:
    """``[x, y, theta]`` rounded to 0.1 mm / 0.1 mrad."""
    return (rounded(p.x), rounded(p.y), rounded(p.theta))


def step_doc(s: ExecutedStep) -> StepDoc:
    """One executed action (failed attempts included)."""
    out: dict[str, Any] = {"action": s.action}
    if s.object is not None:
        out["object"] = s.object
    if s.goal is not None:
        out["goal"] = pose_list(s.goal)
    if s.standing is not None:
        out["standing"] = pose_list(s.standing)
    if s.pose is not None:
        out["pose"] = tuple(rounded(v) for v in s.pose)
    out |= {"duration_s": round(s.duration_s, 3), "ok": s.ok, "attempt": s.attempt}
    if s.note:
        out["note"] = s.note
    if s.path:
        out["path"] = [(rounded(x), rounded(y)) for x, y in s.path]
    if s.reason is not None:
        out["reason"] = s.reason
    if s.arrival_error_m is not None:
        out["arrival_error_m"] = rounded(s.arrival_error_m)
    if s.arrival_yaw_error_rad is not None:
        out["arrival_yaw_error_rad"] = rounded(s.arrival_yaw_error_rad)
    if s.tray:
        out["tray"] = True
    return StepDoc(**out)


def plan_doc(plan: Plan) -> PlanDoc:
    """The chosen plan: order, standing positions and its expected utility, feasibility and
    cost (seconds), and which of the M configurations it realises."""
    standing = {s.object: pose_list(s.standing) for s in plan.steps
                if s.action == "place" and s.standing is not None}
    return PlanDoc(
        order=list(plan.order),
        standing=[StandingDoc(object=o, pose=standing[o]) for o in plan.order if o in standing],
        configuration_index=plan.configuration_index,
        configurations=plan.configurations_considered,
        expected_utility=round(plan.utility, 3),
        feasibility=round(plan.feasibility, 4),
        expected_cost_s=round(plan.cost_s, 3),
        expected_duration_s=round(sum(s.duration_s for s in plan.steps)
                                  if plan.expected_duration_s is None
                                  else plan.expected_duration_s, 3),
        fidelity=PlanFidelityDoc(
            weight_s_per_cm=plan.fidelity_w_s_per_cm,
            chosen=fidelity_doc(plan.fidelity, gaps=True),
            configurations=[considered_doc(c) for c in plan.considered]))


def _r(value: float | None, digits: int = 4) -> float | None:
    return None if value is None else round(value, digits)


def fidelity_doc(f: Fidelity, *, gaps: bool = False) -> FidelityDoc:
    """``f`` as the contract's document; ``gaps`` adds the per-relation figures."""
    return FidelityDoc(
        infidelity_m=round(f.infidelity_m, 4), max_gap_error_m=round(f.max_gap_error_m, 4),
        origin=f.origin, origin_shift_m=round(f.origin_shift_m, 4),
        edge_stated_m=_r(f.edge_stated_m), edge_realised_m=_r(f.edge_realised_m),
        gaps=[GapDoc(subject=g.subject, relation=g.relation, reference=g.reference,
                     stated_m=round(g.stated_m, 4), realised_m=round(g.realised_m, 4),
                     error_m=round(g.error_m, 4)) for g in f.gaps] if gaps else None)


def considered_doc(c: Considered) -> ConsideredDoc:
    """One configuration as GROP scored it, as the contract's document."""
    return ConsideredDoc(index=c.index, expected_utility=_r(c.utility, 3),
                         feasibility=_r(c.feasibility), expected_cost_s=_r(c.cost_s, 3),
                         score=_r(c.score, 3), fidelity=fidelity_doc(c.fidelity))


def run_doc(r: RunResult, *, llm_log: bool = True) -> RunDoc:
    """The run JSON's document of ``r``; ``llm_log=False`` leaves the LLM's call log out of
    ``planned`` (its backend, model and call count stay)."""
    ex = r.execution
    # Only a robot that carries several objects per trip says its trips: the rows of one
    # object per trip stay as they were.
    several = {"trips": [list(t) for t in ex.trips]} if r.scene.robot.capacity > 1 else {}
    return RunDoc(
        **several,
        method=r.method, task=r.task, seed=r.seed, request=r.request,
        success=ex.success,
        execution_time_s=round(ex.execution_time_s, 3),
        planning_time_s=round(r.planning_time_s, 4),
        failures=ex.failures,
        unplaced=list(ex.unplaced),
        unplaced_reasons=dict(ex.unplaced_reasons),
        steps=[step_doc(s) for s in ex.steps],
        final=arrangement_doc(replace(r.final, llm=None), physical=True),
        plan=plan_doc(r.plan),
        planned=arrangement_doc(r.planned, llm_log=llm_log),
        simulator=r.simulator,
        feasibility=r.feasibility,
        scene=SceneFile.model_validate(scene_to_dict(r.scene)))


def run_to_dict(r: RunResult) -> dict[str, Any]:
    """The run JSON as a dict."""
    return run_doc(r).to_json()
