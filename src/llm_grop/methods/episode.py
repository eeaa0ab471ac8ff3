"""One episode: a method's arrangement, the task-motion plan, and its simulated execution.

Random streams are separate per stage (:mod:`llm_grop.seeds`), so every method run on the
same seed sees the same scene and chairs, and the comparison is paired.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, replace

from llm_grop import seeds
from llm_grop.arrangement.diners import violations_at_table
from llm_grop.arrangement.revision import Feedback, rounds_for
from llm_grop.execution import ExecutionPolicy, execute
from llm_grop.methods.base import EpisodeInput, Method
from llm_grop.methods.reach import PlannerReach
from llm_grop.methods.rescue import Rescuer, rescuer
from llm_grop.planning.feasibility import FeasibilityModel, feasibility_profile
from llm_grop.planning.grop import build_plan
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.utility import GropOptions, PlanningContext
from llm_grop.recording.stream import EpisodeEnd, EpisodeObserver, EpisodeStart, ObjectShape
from llm_grop.simulation.base import Simulator
from llm_grop.world.arrangement import Arrangement, Configuration
from llm_grop.world.plan import Execution, Plan, RunResult
from llm_grop.world.relation import Relation
from llm_grop.world.scene import Scene

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PlannedEpisode:
    """A method's plan before execution: the arrangement it proposed, the chosen plan, the
    episode's scene (its chairs are the sensed ones), the planning time in seconds (LLM
    calls excluded) and the name of the planner's feasibility profile."""

    arrangement: Arrangement
    plan: Plan
    scene: Scene
    planning_time_s: float
    feasibility: str = "default"


def plan_episode(method: Method, inp: EpisodeInput, scene: Scene, *,
                 model: FeasibilityModel | str = "default",
                 planner: GropOptions | None = None) -> PlannedEpisode:
    """The first half of an episode: ``method``'s arrangement and the task-motion plan for
    it in ``scene`` (its chairs are sensed at planning time), not executed.

    ``model`` is the planner's belief of how often actions succeed, a model or the name of
    a profile (:func:`~llm_grop.planning.feasibility.feasibility_profile`). Planning time
    counts the arrangement's computation without LLM calls, GROP and the OMPL paths.
    Raises :class:`~llm_grop.errors.Infeasible` when no plan exists.
    """
    t0 = time.perf_counter()
    profile = model if isinstance(model, str) else "custom"
    belief = feasibility_profile(model) if isinstance(model, str) else model
    ctx = PlanningContext(scene, inp.items, belief, planner)
    context_s = time.perf_counter() - t0
    if inp.llm is not None and rounds_for(inp.options.revisions, inp.llm.model) > 0:
        # With the feedback loop, an arrangement the robot cannot reach is told to the LLM.
        inp = replace(inp, options=replace(inp.options, reach=PlannerReach(ctx)))
    proposal = method.arrangement.propose(inp)
    _say(inp, f"planning for {len(proposal.configurations)} configuration(s)")
    t0 = time.perf_counter() - context_s
    cand = method.standing_choice.choose(ctx, proposal, seeds.stream(inp.seed, "standing"))
    plan = build_plan(ctx, cand, navigator(scene, planner), inp.seed,
                      len(proposal.configurations))
    planning_s = proposal.compute_time_s + time.perf_counter() - t0
    return PlannedEpisode(proposal.arrangement, plan, scene, planning_s, profile)


def navigator(scene: Scene, planner: GropOptions | None = None) -> Navigator:
    """The robot's own path planner in ``scene``, as GROP plans with it and the executive
    replans with it."""
    return Navigator(scene, scene.robot.base_radius_m,
                     time_limit_s=(planner or GropOptions()).path_time_limit_s)


def execute_episode(planned: PlannedEpisode, inp: EpisodeInput, *, task: int | None,
                    simulator: Simulator, method: str, attempts: int,
                    planner: GropOptions | None = None,
                    policy: ExecutionPolicy | None = None,
                    observer: EpisodeObserver | None = None) -> RunResult:
    """The second half of an episode: ``planned`` (:func:`plan_episode`) executed by the
    executive on ``simulator``, which decides what really happens, with ``attempts`` per
    pick and place unless ``policy`` sets them; the simulator's randomness comes from the
    seed's ``simulator`` stream, so the same seed gives the same run. ``observer`` hears
    the episode as it runs (:mod:`llm_grop.recording`); it changes nothing in it."""
    plan, scene = planned.plan, planned.scene
    _say(inp, f"executing the plan (configuration {plan.configuration_index}, from 0; "
              f"expected utility {plan.utility:.1f} s) with {simulator.name}")
    if observer is not None:
        observer.begin(EpisodeStart(
            scene, tuple(ObjectShape.of_item(i) for i in inp.items), plan,
            planned.arrangement.relations, method, task, inp.seed, inp.request,
            simulator.name, planned.feasibility, simulator.streams))
    rescue = _rescuer(planned, inp, planner)
    asked = len(inp.llm.calls) if inp.llm is not None else 0
    execution = execute(simulator, plan, scene, inp.items, seeds.stream(inp.seed, "simulator"),
                        replan=navigator(scene, planner),
                        policy=(policy or ExecutionPolicy()).for_method(attempts),
                        observer=observer, rescue=rescue)
    if observer is not None:
        observer.end(execution.execution_time_s, EpisodeEnd(
            execution.success, execution.execution_time_s, execution.unplaced_reasons))
    arranged = replace(planned.arrangement, placements=plan.configuration)
    if rescue is not None and len(rescue.feedback.done) > len(arranged.revisions):
        arranged = _rescued(arranged, rescue, inp, asked)
    return RunResult(method=method, task=task, seed=inp.seed, request=inp.request,
                     planned=arranged, plan=plan, execution=execution,
                     final=final_arrangement(arranged, execution),
                     planning_time_s=planned.planning_time_s, scene=scene,
                     simulator=simulator.name, feasibility=planned.feasibility)


def _rescuer(planned: PlannedEpisode, inp: EpisodeInput, planner: GropOptions | None
             ) -> Rescuer | None:
    """The feedback loop's rescue for the executive, when the arrangement came from the LLM
    and rounds are left (``revisions``); ``None`` otherwise."""
    a = planned.arrangement
    if inp.llm is None:
        return None
    rounds = rounds_for(inp.options.revisions, inp.llm.model)
    if rounds <= len(a.revisions):
        return None
    feedback = Feedback(inp.llm, inp.catalog, inp.seed, inp.options.params, rounds,
                        lambda m: _say(inp, m), list(a.revisions))
    return rescuer(feedback, inp.items, a.relations, planned.plan.configuration, a.table,
                   planned.scene, feasibility_profile(planned.feasibility),
                   planner or GropOptions(), inp.seed)


def _rescued(arranged: Arrangement, rescue: Rescuer, inp: EpisodeInput, asked: int
             ) -> Arrangement:
    """``arranged`` as the rescue left it: its relations, targets, rounds, warnings and
    the LLM calls the rounds made (those of ``inp.llm`` from the ``asked``-th on)."""
    llm = arranged.llm
    if llm is not None and inp.llm is not None:
        llm = replace(llm, calls=llm.calls + tuple(inp.llm.calls[asked:]))
    return replace(arranged, relations=tuple(rescue.relations),
                   placements=tuple(rescue.targets[p.name] for p in arranged.placements),
                   revisions=tuple(rescue.feedback.done),
                   warnings=arranged.warnings + tuple(rescue.feedback.warnings), llm=llm)


def _say(inp: EpisodeInput, message: str) -> None:
    log.info(message)
    if inp.on_event is not None:
        inp.on_event(message)


def final_arrangement(planned: Arrangement, execution: Execution) -> Arrangement:
    """Where the objects really are, with the planned relations that still hold there."""
    config = Configuration(execution.final)
    names = {p.name for p in execution.final}
    kept = tuple(r for r in planned.relations
                 if r.subject in names and (r.reference is None or r.reference in names)
                 and not _breaks(config, r, planned))
    return replace(planned, placements=execution.final, relations=kept, warnings=(),
                   conflicts=(), revisions=())


def _breaks(config: Configuration, relation: Relation, planned: Arrangement) -> bool:
    """Whether ``relation`` fails between its objects' final places (or they overlap or
    left the table)."""
    pair = {relation.subject, relation.reference}
    sub = Configuration(tuple(p for p in config.placements if p.name in pair))
    return bool(violations_at_table(sub, [relation], planned.table))
