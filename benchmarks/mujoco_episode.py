"""MuJoCo episode figures: wall time, real-time factor, render time and placement error.

Runs Task 8 (``--task``) with LLM-GROP (the embedded model's recorded answers, 1 chair) on
seeds 0..N-1 in the 3D simulator and prints the median wall time of a whole episode (arrange,
plan, execute), the real-time factor of execution (simulated / wall seconds), the time to
render one frame (table, room, video-sized room), and the distance between each object's
planned pose and its settled pose, for objects whose place succeeded.
Run: .venv/bin/python benchmarks/mujoco_episode.py [--seeds 10] [--task 8] [--feasibility default]
     [--pictures 5] [--frames 20] [--quick]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

from common import parse_args, replay_llm

from llm_grop.api import run
from llm_grop.simulation.mujoco.render import new_renderer, picture, render_with
from llm_grop.simulation.mujoco.simulator import MujocoSimulator


class TimedSimulator(MujocoSimulator):
    """Records the wall time of each episode's execution, from its session's start to its
    end."""

    def session(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        t0 = time.perf_counter()
        session = super().session(*args, **kwargs)
        close = session.close

        def timed_close() -> None:
            close()
            self.last_wall_s = time.perf_counter() - t0

        session.close = timed_close  # type: ignore[method-assign]
        return session


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--task", type=int, default=8)
    ap.add_argument("--feasibility", default="default")
    ap.add_argument("--pictures", type=int, default=5, help="pictures timed per view")
    ap.add_argument("--frames", type=int, default=20, help="video frames timed per size")
    args = parse_args(ap, {"seeds": 1, "task": 1, "pictures": 1, "frames": 1})
    llm = replay_llm()
    sim = TimedSimulator()
    walls, rtfs, errors, successes, sim_times = [], [], [], 0, []
    for seed in range(args.seeds):
        t0 = time.perf_counter()
        r = run(task=args.task, seed=seed, llm=llm, simulator=sim, feasibility=args.feasibility)
        walls.append(time.perf_counter() - t0)
        rtfs.append(r.execution.execution_time_s / sim.last_wall_s)
        sim_times.append(r.execution.execution_time_s)
        successes += r.success
        planned = {p.name: p for p in r.plan.configuration}
        placed_ok = {s.object for s in r.execution.steps if s.action == "place" and s.ok}
        for p in r.final.placements:
            if p.name in placed_ok:
                q = planned[p.name]
                errors.append(1000 * math.hypot(p.x - q.x, p.y - q.y))
        print(f"seed {seed}: {walls[-1]:.2f} s wall, {r.execution.execution_time_s:.1f} s "
              f"simulated, success {r.success}, failures {r.execution.failures}")
    assert sim.world is not None
    renders = {}
    for label, view in (("table", "table"), ("room", "room")):
        t0 = time.perf_counter()
        for _ in range(args.pictures):
            picture(sim.world, view)  # each opens and closes its own GL context
        renders[f"{label} picture 640x480, with its GL context"] = (
            time.perf_counter() - t0) / args.pictures
    for w, h in ((640, 480), (320, 240)):
        renderer = new_renderer(sim.world.m, (w, h))
        render_with(renderer, sim.world, "room")
        t0 = time.perf_counter()
        for _ in range(args.frames):
            render_with(renderer, sim.world, "room")
        renders[f"video frame {w}x{h}"] = (time.perf_counter() - t0) / args.frames
        renderer.close()
    print(f"\nTask {args.task} x {args.seeds} seeds, LLM-GROP, MuJoCo, feasibility "
          f"{args.feasibility}")
    print(f"  wall time per episode: median {statistics.median(walls):.2f} s "
          f"(min {min(walls):.2f}, max {max(walls):.2f})")
    print(f"  real-time factor of execution: median {statistics.median(rtfs):.0f}x")
    print(f"  success {successes}/{args.seeds}; simulated execution time mean "
          f"{statistics.fmean(sim_times):.1f} s")
    for label, s in renders.items():
        print(f"  render {label}: {1000 * s:.0f} ms per frame")
    print(f"  placement error, planned vs settled ({len(errors)} objects placed): "
          f"mean {statistics.fmean(errors):.1f} mm, max {max(errors):.1f} mm")


if __name__ == "__main__":
    main()
