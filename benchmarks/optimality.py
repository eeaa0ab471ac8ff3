"""How close LLM-GROP's execution time is to the exact optimum, on a 4-object task.

For each seed, LLM-GROP plans Task 7 (dinner plate, dinner fork, dinner knife,
strawberry; the embedded model's recorded answers) with 1 chair. For the configuration it
chose, the optimum is found by enumerating every order (4! = 24) and, for each, every
standing position of every object. The objective is a sum of legs in which each object's
standing position appears only in its own two legs, so minimising each object's legs over
all positions, for each order, covers the whole product space exactly. Two optima:
* *optimum*: least expected execution time, where driving takes path length / speed and a
  place at reach r takes ``place_time * (1 - (1 - p)^A) / p`` seconds, ``p`` being the
  feasibility model's success probability and ``A`` the simulator's attempts (the
  simulator's retries; navigation failures replan from where the robot stopped, so they
  cost little time and are left out);
* *failure-free fastest*: least duration when nothing fails (``p`` ignored).
Each plan gets OMPL paths and is executed ``--executions`` times by the simulator with the
same seeds (paired); the figure is the mean simulated execution time, seconds.
Run: .venv/bin/python benchmarks/optimality.py [--seeds 10] [--executions 50] [--quick]
"""

from __future__ import annotations

import argparse
import itertools
import statistics
from dataclasses import replace

import numpy as np
from common import parse_args, replay_llm

from llm_grop import seeds
from llm_grop.api import resolve_items, run
from llm_grop.execution import execute
from llm_grop.execution.policy import BASELINE_MANIP_ATTEMPTS
from llm_grop.planning.grop import Candidate, build_plan, evaluate
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.standing import reach
from llm_grop.planning.utility import PlanningContext
from llm_grop.simulation.kinematic2d import Kinematic2D
from llm_grop.world.arrangement import Configuration
from llm_grop.world.catalog import Catalog
from llm_grop.world.plan import Plan


def fastest(ctx: PlanningContext, base: Candidate, *, failures: bool) -> Candidate:
    """The plan of least (expected, with ``failures``) duration for ``base``'s configuration,
    over every order and every standing position."""
    placements = base.placements
    feas = ctx.place_feasibility(placements)
    robot = ctx.scene.robot
    manip = ctx.model.manipulation(reach(ctx.candidates, ctx.targets_room(placements)).T,
                                   robot)
    attempts = BASELINE_MANIP_ATTEMPTS
    with np.errstate(divide="ignore", invalid="ignore"):
        place_s = np.where(manip > 0, robot.place_time_s * (1 - (1 - manip) ** attempts)
                           / manip, np.inf)
    if not failures:
        place_s = np.where(feas > 0, robot.place_time_s, np.inf)
    v = ctx.speed
    field = [p.field for p in ctx.pickups]
    best: tuple[float, tuple[int, ...], list[int]] | None = None
    names = [p.name for p in placements]
    for order in itertools.permutations(range(len(placements))):
        pos = {names[j]: k for k, j in enumerate(order)}
        if any(p.on is not None and pos[p.on] > pos[p.name] for p in placements):
            continue
        total = ctx.start_dist_m[field[order[0]]] / v
        stands = [0] * len(order)
        for k, j in enumerate(order):
            legs = ctx.dist_m[:, field[j]] / v + place_s[j]
            if k + 1 < len(order):
                legs = legs + ctx.dist_m[:, field[order[k + 1]]] / v
            stands[j] = int(np.argmin(legs))
            total += float(legs[stands[j]])
        if best is None or total < best[0]:
            best = (total, order, stands)
    assert best is not None
    _, order, stands = best
    place_p = tuple(float(feas[j, stands[j]]) for j in range(len(order)))
    return replace(base, order=order, stand=tuple(stands),
                   alternatives=tuple(() for _ in order), place_p=place_p)


def simulate(plan: Plan, ctx: PlanningContext, nav: Navigator, runs: int) -> float:
    """Mean simulated execution time of ``plan`` over ``runs`` seeds, seconds (the
    executive with the baselines' attempt counts)."""
    sim = Kinematic2D()
    return statistics.fmean(
        execute(sim, plan, ctx.scene, ctx.items, seeds.stream(seed, "simulator"), replan=nav
                ).execution_time_s for seed in range(runs))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--executions", type=int, default=50)
    args = parse_args(ap, {"seeds": 1, "executions": 2})
    llm = replay_llm()
    items = resolve_items(None, 7, Catalog.load())[1]
    gaps_opt, gaps_fast = [], []
    for seed in range(args.seeds):
        r = run(task=7, method="llm-grop", seed=seed, chairs=1, llm=llm)
        ctx = PlanningContext(r.scene, items)
        chosen = evaluate(ctx, Configuration(r.plan.configuration), r.plan.configuration_index)
        assert isinstance(chosen, Candidate)
        nav = Navigator(r.scene, r.scene.robot.base_radius_m)
        ours = simulate(build_plan(ctx, chosen, nav, seed, 1), ctx, nav, args.executions)
        opt = simulate(build_plan(ctx, fastest(ctx, chosen, failures=True), nav, seed, 1),
                       ctx, nav, args.executions)
        fast = simulate(build_plan(ctx, fastest(ctx, chosen, failures=False), nav, seed, 1),
                        ctx, nav, args.executions)
        gaps_opt.append(ours / opt - 1)
        gaps_fast.append(ours / fast - 1)
        print(f"seed {seed}: LLM-GROP {ours:.1f} s, optimum {opt:.1f} s "
              f"({100 * gaps_opt[-1]:+.1f}%), failure-free fastest {fast:.1f} s "
              f"({100 * gaps_fast[-1]:+.1f}%)")
    print(f"simulated execution time: LLM-GROP is {100 * statistics.fmean(gaps_opt):+.1f}% "
          f"from the exhaustive optimum on average (worst {100 * max(gaps_opt):+.1f}%; "
          f"target within 5%); {100 * statistics.fmean(gaps_fast):+.1f}% from the "
          "failure-free fastest plan")


if __name__ == "__main__":
    main()
