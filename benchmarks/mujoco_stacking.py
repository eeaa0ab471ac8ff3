"""Stacking in MuJoCo: the lid on the mug, the mug on its mat, the bread on its plate.

For each pair, a plan puts the support at a random spot on the dining table and the other
object on it (as an arrangement's "on top of" relation would), in the packaged dining room
with one chair and the authors' arrival noise; success = the settled top object rests on
its support by contact.
Run: .venv/bin/python benchmarks/mujoco_stacking.py [--seeds 20] [--pairs 3] [--quick]
"""

from __future__ import annotations

import argparse

from common import parse_args

from llm_grop import seeds
from llm_grop.execution import execute
from llm_grop.files.scene_file import load_scene
from llm_grop.planning.grop import build_plan, choose
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.utility import PlanningContext
from llm_grop.simulation.mujoco.simulator import MujocoSimulator
from llm_grop.simulation.scenario import prepare_episode
from llm_grop.world.arrangement import Configuration, Placement
from llm_grop.world.catalog import Catalog
from llm_grop.world.request import items_from_names

PAIRS = (("mug lid", "mug"), ("mug", "mug mat"), ("bread", "bread plate"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--pairs", type=int, default=len(PAIRS), help="the first N pairs")
    args = parse_args(ap, {"seeds": 1, "pairs": 1})
    catalog = Catalog.load()
    room = load_scene(None)
    sim = MujocoSimulator()
    for top, support in PAIRS[:args.pairs]:
        items = items_from_names([support, top], catalog)
        stacked = placed = 0
        for seed in range(args.seeds):
            rng = seeds.stream(seed, "sampler")
            x, y = float(rng.uniform(-0.25, 0.25)), float(rng.uniform(-0.15, 0.1))
            specs = {i.name: i.spec for i in items}
            cfg = Configuration(tuple(
                Placement(n, x, y, 0.0, specs[n].shape, specs[n].size,
                          support if n == top else None, specs[n].name, specs[n].height)
                for n in (support, top)))
            scene = prepare_episode(room, items, seed, chairs=1)
            ctx = PlanningContext(scene, items)
            nav = Navigator(scene, scene.robot.base_radius_m)
            plan = build_plan(ctx, choose(ctx, [cfg]), nav, seed=seed, configurations=1)
            ex = execute(sim, plan, scene, items, seeds.stream(seed, "simulator"),
                         replan=nav)
            final = {p.name: p for p in ex.final}
            if top in final and support in final:
                placed += 1
                stacked += final[top].on == support
        print(f"{top} on {support}: {stacked}/{args.seeds} stacked "
              f"({placed} episodes placed both)")


if __name__ == "__main__":
    main()
