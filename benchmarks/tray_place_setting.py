"""One place setting on the tray: loads, unloads and outcomes per seed, MuJoCo and 2D.

``run "a dinner plate, a dinner fork, a dinner knife and a water cup" --method grop
--chairs 0 --capacity 4`` for each seed and simulator, with two robots: the packaged one
(``packaged``: its 8 s picks and places, the simulator's fitted belief; trips seldom pay
for their loads) and ``quick`` (0.1 s picks and places, the default belief: the planner
makes trips, as ``tests/simulation/test_tray.py`` runs it). Per run: each object's loads
and unloads, succeeded / attempted, its fate, and whether all were placed; then the
simulated seconds of each load and unload against the belief's ``times.load_s`` and
``times.unload_s``, with which the planner prices them.

    PYTHONPATH=src python benchmarks/tray_place_setting.py --seeds 6
"""

from __future__ import annotations

import argparse
import statistics
from collections import defaultdict
from dataclasses import replace

from common import parse_args

from llm_grop.api import run
from llm_grop.files.scene_file import load_scene
from llm_grop.planning.feasibility import action_times, feasibility_profile
from llm_grop.world.plan import RunResult

SETTING = "a dinner plate, a dinner fork, a dinner knife and a water cup"
SIMULATORS = {"mujoco": "mujoco", "2d": "kinematic2d"}


def one(seed: int, simulator: str, robot: str) -> RunResult:
    """The place setting's run at ``seed`` on ``simulator`` with ``robot``'s times."""
    scene = load_scene()
    extra: dict[str, object] = {}
    if robot == "quick":
        scene = replace(scene, robot=replace(scene.robot, pick_time_s=0.1, place_time_s=0.1))
        extra["feasibility"] = "default"
    return run(SETTING, method="grop", seed=seed, chairs=0, capacity=4, scene=scene,
               simulator=simulator, **extra)


def report(r: RunResult, seed: int, sim: str, robot: str,
           durations: dict[tuple[str, str, str], list[float]]) -> None:
    """Print one run's line per object; gather its loads' and unloads' seconds."""
    ex = r.execution
    unplaced = dict(ex.unplaced_reasons)
    names = sorted({s.object for s in ex.steps if s.object})
    trips = " ".join("(" + ", ".join(t) + ")" for t in ex.trips)
    print(f"{sim:6s} {robot:8s} seed {seed}: all placed {ex.success}; trips {trips}")
    for n in names:
        tray = [s for s in ex.steps if s.object == n and s.tray]
        loads = [s for s in tray if s.action == "place"]
        unloads = [s for s in tray if s.action == "pick"]
        for s in tray:
            kind = "load" if s.action == "place" else "unload"
            durations[(sim, robot, kind)].append(s.duration_s)
        fails = ", ".join(sorted({s.reason for s in tray if not s.ok and s.reason}))
        fate = f"unplaced ({unplaced[n]})" if n in unplaced else "placed"
        print(f"    {n:13s} loads {sum(s.ok for s in loads)}/{len(loads)}  unloads "
              f"{sum(s.ok for s in unloads)}/{len(unloads)}  {fate}"
              + (f"  tray failures: {fails}" if fails else ""))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=6)
    ap.add_argument("--simulators", default="mujoco,2d")
    ap.add_argument("--robots", default="quick,packaged")
    args = parse_args(ap, quick={"seeds": 1, "simulators": "2d", "robots": "quick"})
    durations: dict[tuple[str, str, str], list[float]] = defaultdict(list)
    belief: dict[tuple[str, str], tuple[str, float, float]] = {}
    for sim in args.simulators.split(","):
        for robot in args.robots.split(","):
            for seed in range(args.seeds):
                r = one(seed, SIMULATORS[sim], robot)
                report(r, seed, sim, robot, durations)
                times = action_times(feasibility_profile(r.feasibility), r.scene.robot)
                belief[(sim, robot)] = (r.feasibility, times.load_s, times.unload_s)
    print("\nsimulated seconds per tray step (ok or not) vs the belief's times.load_s "
          "(load) / times.unload_s (unload)")
    for (sim, robot), (profile, load_s, unload_s) in belief.items():
        for kind, priced in (("load", load_s), ("unload", unload_s)):
            d = durations.get((sim, robot, kind), [])
            if not d:
                print(f"{sim:6s} {robot:8s} {kind:6s}: none (belief {profile}: {priced:.2f} s)")
                continue
            print(f"{sim:6s} {robot:8s} {kind:6s}: n {len(d):2d}  mean {statistics.fmean(d):6.2f}"
                  f"  median {statistics.median(d):6.2f}  min {min(d):6.2f}  max {max(d):6.2f}"
                  f"  belief {profile}: {priced:.2f} s")


if __name__ == "__main__":
    main()
