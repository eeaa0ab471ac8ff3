"""How close LLM-GROP's execution time is to the exact optimum, on a 4-object task.

For each seed, LLM-GROP plans Task 7 (dinner plate, dinner fork, dinner knife,
strawberry; the embedded model's recorded answers). For the configuration it chose,
the exact fastest plan is found by enumerating every order (4! = 24) and, for each,
every standing position of every object (the duration is a sum of legs in which each
object's standing position appears only in its own two legs, so minimising each
object's legs over all positions, for each order, covers the whole product space).
Both plans get OMPL paths and are compared on
* expected duration: the plan's steps without failures, seconds;
* simulated execution time: mean over 20 executions with the feasibility model's
  failures, retries and noise, seconds.
Run: .venv/bin/python benchmarks/optimality.py [--seeds 10]
"""

from __future__ import annotations

import argparse
import itertools
import statistics
from dataclasses import replace

import numpy as np
from common import replay_llm

from llm_grop.api import resolve_items, run
from llm_grop.planning.grop import Candidate, build_plan, evaluate
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.utility import PlanningContext
from llm_grop.simulation.kinematic2d import Kinematic2D
from llm_grop.world.arrangement import Configuration
from llm_grop.world.catalog import Catalog
from llm_grop.world.plan import Plan


def fastest(ctx: PlanningContext, base: Candidate) -> Candidate:
    """The plan of least duration for ``base``'s configuration: every order, every stand."""
    placements = base.placements
    feas = ctx.place_feasibility(placements)
    v = ctx.speed
    field = [p.field for p in ctx.pickups]
    usable = feas > 0
    best: tuple[float, tuple[int, ...], list[int]] | None = None
    names = [p.name for p in placements]
    for order in itertools.permutations(range(len(placements))):
        pos = {names[j]: k for k, j in enumerate(order)}
        if any(p.on is not None and pos[p.on] > pos[p.name] for p in placements):
            continue
        total = ctx.start_dist_m[field[order[0]]] / v
        stands = [0] * len(order)
        for k, j in enumerate(order):
            legs = ctx.dist_m[:, field[j]] / v
            if k + 1 < len(order):
                legs = legs + ctx.dist_m[:, field[order[k + 1]]] / v
            legs = np.where(usable[j], legs, np.inf)
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
    """Mean simulated execution time of ``plan`` over ``runs`` seeds, seconds."""
    sim = Kinematic2D()
    return statistics.fmean(
        sim.execute(plan, ctx.scene, np.random.default_rng([seed, 99]), replan=nav,
                    model=ctx.model).execution_time_s for seed in range(runs))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--executions", type=int, default=20)
    args = ap.parse_args()
    llm = replay_llm()
    items = resolve_items(None, 7, Catalog.load())[1]
    gaps_expected, gaps_sim = [], []
    for seed in range(args.seeds):
        r = run(task=7, method="llm-grop", seed=seed, chairs=1, llm=llm)
        ctx = PlanningContext(r.scene, items)
        chosen = evaluate(ctx, Configuration(r.plan.configuration), r.plan.configuration_index)
        assert isinstance(chosen, Candidate)
        nav = Navigator(r.scene, r.scene.robot.base_radius_m)
        ours = build_plan(ctx, chosen, nav, seed, 1)
        opt = build_plan(ctx, fastest(ctx, chosen), nav, seed, 1)
        e_ours = sum(s.duration_s for s in ours.steps)
        e_opt = sum(s.duration_s for s in opt.steps)
        s_ours = simulate(ours, ctx, nav, args.executions)
        s_opt = simulate(opt, ctx, nav, args.executions)
        gaps_expected.append(e_ours / e_opt - 1)
        gaps_sim.append(s_ours / s_opt - 1)
        print(f"seed {seed}: expected {e_ours:.1f} s vs optimum {e_opt:.1f} s "
              f"({100 * gaps_expected[-1]:+.1f}%); simulated {s_ours:.1f} s vs "
              f"{s_opt:.1f} s ({100 * gaps_sim[-1]:+.1f}%)")
    print(f"expected duration: LLM-GROP is {100 * statistics.fmean(gaps_expected):+.1f}% "
          f"(worst {100 * max(gaps_expected):+.1f}%) from the fastest plan")
    print(f"simulated execution time: LLM-GROP is {100 * statistics.fmean(gaps_sim):+.1f}% "
          f"(worst {100 * max(gaps_sim):+.1f}%) from the fastest plan; target within 5%")


if __name__ == "__main__":
    main()
