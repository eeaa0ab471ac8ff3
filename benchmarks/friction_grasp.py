"""Which catalog objects each MuJoCo grasp can carry.

For every catalog kind the 3D world accepts, the robot stands at the calibration table
facing the object 0.55 m away, picks it, drives to one end of the room and then the other
(about 6 m, turning on the spot at each goal, at full speed and acceleration) and reports
whether the object is still in hand:
``carried``; ``missed`` (the grasp did not hold while lifting); ``dropped`` (lost in
transit); or the pick's other failure. Run it for both grasps; the README's list of what
``--grasp friction`` can carry comes from it.
Run: .venv/bin/python benchmarks/friction_grasp.py [--grasp fix,friction] [--kinds K1,K2] [--quick]
"""

from __future__ import annotations

import argparse
import math

import numpy as np
from common import parse_args

from llm_grop.errors import BadInput
from llm_grop.experiment.calibration import room
from llm_grop.planning.navigation import Navigator
from llm_grop.simulation.mujoco.options import MujocoOptions
from llm_grop.simulation.mujoco.simulator import MujocoSimulator
from llm_grop.simulation.mujoco.tableware import tableware
from llm_grop.world.arrangement import item_placement
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.request import items_from_names
from llm_grop.world.scene import ObjectSource


def outcome(kind: str, grasp: str, catalog: Catalog) -> str:
    """How one pick and carry of ``kind`` ended."""
    scene = room((ObjectSource(kind, "dining table", 3.0, 1.85),), Pose2D(3.0, 1.3, math.pi / 2))
    items = items_from_names([kind], catalog)
    session = MujocoSimulator(MujocoOptions(grasp=grasp)).session(  # type: ignore[arg-type]
        scene, items, np.random.default_rng(0), replan=Navigator(scene, 0.3))
    pick = session.pick(kind)
    if not pick.ok:
        return "missed" if pick.reason == "grasp_missed" else str(pick.reason)
    for goal in (Pose2D(1.0, 0.6, math.pi), Pose2D(5.0, 0.6, 0.0)):
        drive = session.navigate(goal)
        if drive.reason == "fell":
            return "dropped"
    return "carried" if session.held == kind else "dropped"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grasp", default="fix,friction")
    ap.add_argument("--kinds", default=None, help="the catalog kinds to try (default: all)")
    args = parse_args(ap, {"grasp": "fix", "kinds": "dinner fork"})
    catalog = Catalog.load()
    kinds = args.kinds.split(",") if args.kinds else catalog.names()
    grasps = args.grasp.split(",")
    print("| object | " + " | ".join(grasps) + " |")
    print("| --- | " + " | ".join("---" for _ in grasps) + " |")
    counts = {g: 0 for g in grasps}
    n = 0
    for kind in kinds:
        try:
            tableware(item_placement(items_from_names([kind], catalog)[0]))
        except BadInput:
            continue  # too large for the gripper: refused before any episode
        n += 1
        cells = []
        for g in grasps:
            result = outcome(kind, g, catalog)
            counts[g] += result == "carried"
            cells.append(result)
        print(f"| {kind} | " + " | ".join(cells) + " |", flush=True)
    print("carried: " + ", ".join(f"{g} {counts[g]} of {n}" for g in grasps))


if __name__ == "__main__":
    main()
