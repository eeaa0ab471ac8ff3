"""One episode: a method's arrangement, the task-motion plan, and its simulated execution.

Random streams are separate per stage (:mod:`llm_grop.seeds`), so every method run on the
same seed sees the same scene and chairs, and the comparison is paired.
"""

from __future__ import annotations

import logging
import time
from dataclasses import replace

from llm_grop import seeds
from llm_grop.arrangement.diners import violations_at_table
from llm_grop.execution import ExecutionPolicy, execute
from llm_grop.execution.policy import BASELINE_MANIP_ATTEMPTS
from llm_grop.methods.base import EpisodeInput, Method
from llm_grop.planning.feasibility import FeasibilityModel, feasibility_profile
from llm_grop.planning.grop import build_plan, choose
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.utility import GropOptions, PlanningContext
from llm_grop.simulation.base import Simulator
from llm_grop.world.arrangement import Arrangement, Configuration
from llm_grop.world.plan import Execution, RunResult
from llm_grop.world.relation import Relation
from llm_grop.world.scene import Scene

log = logging.getLogger(__name__)


def run_episode(method: Method, inp: EpisodeInput, scene: Scene, *, task: int | None,
                simulator: Simulator, model: FeasibilityModel | str = "default",
                planner: GropOptions | None = None,
                policy: ExecutionPolicy | None = None) -> RunResult:
    """Arrange, plan and execute in ``scene`` (its chairs are sensed at planning time).

    ``model`` is the planner's belief of how often actions succeed, a model or the name of
    a profile (:func:`~llm_grop.planning.feasibility.feasibility_profile`); ``simulator`` decides
    what really happens, and the executive runs the plan on it under ``policy`` (default:
    the authors' attempt counts, the method's for manipulation).

    Planning time counts the arrangement's computation without LLM calls, GROP and the
    OMPL paths. Raises :class:`~llm_grop.errors.Infeasible` when no plan exists.
    """
    def say(message: str) -> None:
        log.info(message)
        if inp.on_event is not None:
            inp.on_event(message)

    proposal = method.propose(inp)
    say(f"planning for {len(proposal.configurations)} configuration(s)")
    t0 = time.perf_counter()
    profile = model if isinstance(model, str) else "custom"
    belief = feasibility_profile(model) if isinstance(model, str) else model
    ctx = PlanningContext(scene, inp.items, belief, planner)
    cand = choose(ctx, proposal.configurations, method.standing,
                  seeds.stream(inp.seed, "standing"), method.best_of_all, proposal.fidelity)
    navigator = Navigator(scene, scene.robot.base_radius_m,
                          time_limit_s=ctx.options.path_time_limit_s)
    plan = build_plan(ctx, cand, navigator, inp.seed, len(proposal.configurations))
    planning_s = proposal.compute_time_s + time.perf_counter() - t0
    say(f"executing the plan (configuration {plan.configuration_index + 1}, expected "
        f"utility {plan.utility:.1f} s) with {simulator.name}")
    attempts = getattr(method, "manip_attempts", BASELINE_MANIP_ATTEMPTS)
    execution = execute(simulator, plan, scene, inp.items, seeds.stream(inp.seed, "simulator"),
                        replan=navigator,
                        policy=(policy or ExecutionPolicy()).for_method(attempts))
    planned = replace(proposal.arrangement, placements=plan.configuration)
    return RunResult(method=method.name, task=task, seed=inp.seed, request=inp.request,
                     planned=planned, plan=plan, execution=execution,
                     final=final_arrangement(planned, execution),
                     planning_time_s=planning_s, scene=scene, simulator=simulator.name,
                     feasibility=profile)


def final_arrangement(planned: Arrangement, execution: Execution) -> Arrangement:
    """Where the objects really are, with the planned relations that still hold there."""
    config = Configuration(execution.final)
    names = {p.name for p in execution.final}
    kept = tuple(r for r in planned.relations
                 if r.subject in names and (r.reference is None or r.reference in names)
                 and not _breaks(config, r, planned))
    return replace(planned, placements=execution.final, relations=kept, warnings=(),
                   conflicts=())


def _breaks(config: Configuration, relation: Relation, planned: Arrangement) -> bool:
    """Whether ``relation`` fails between its objects' final places (or they overlap or
    left the table)."""
    pair = {relation.subject, relation.reference}
    sub = Configuration(tuple(p for p in config.placements if p.name in pair))
    return bool(violations_at_table(sub, [relation], planned.table))
