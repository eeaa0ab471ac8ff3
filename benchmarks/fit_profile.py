"""Task 8 episodes measured through the executive; the belief against what happened, and
the belief re-fitted from it.

Runs Task 8 (seeds 0..N-1, the embedded model's recorded answers) with GROP and LLM-GROP,
1 and 4 chairs, on one simulator, 2 worker processes, planning with one feasibility
profile. Prints, per method and chair count:

* all placed, failed attempts per episode by reason, arrival error (median, p95), execution
  time and wall time per episode;
* predicted against measured: first-attempt success per action kind (mean of the plan's
  step probabilities against the share of first attempts that succeeded), the whole plan's
  P(no failed attempt) (the plan's feasibility against the share of episodes without a
  failed attempt) and expected against measured execution time.

``--fit`` fits a profile by maximum likelihood: navigation success against the goal's
clearance, pick and place success against the reach from where the base really stood (one
reach curve fitted to every attempt; a pick's and a place's top fitted to first
attempts), the actions' mean durations, a drive's overhead over the planned legs driven as
planned, and what a failed attempt costs with its recovery (these two from the episodes
that kept their goals, i.e. saved by this version); it prints tipping after a place by
object kind. ``--write`` stores the fit as the ``mujoco`` profile
in src/llm_grop/data/feasibility.yaml.
``--save FILE`` keeps the measurements; ``--also FILE ...`` fits to earlier runs' too, so
that a profile can be re-fitted to the plans made with it (the belief moves the plans).
``--quick``: one LLM-GROP episode with 1 chair in 2D, and the fit.
Run: .venv/bin/python benchmarks/fit_profile.py [--simulator mujoco] [--seeds 20] [--first-seed 0]
     [--feasibility default] [--truth PROFILE] [--fit] [--write] [--save F] [--also F...]
     [--quick]
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import re
import statistics
import time
from collections import Counter, defaultdict
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from common import median_p95, parse_args, replay_llm
from scipy.optimize import minimize_scalar

from llm_grop.api import run
from llm_grop.errors import Infeasible
from llm_grop.experiment.calibration import Sample, fit, likelihood_p
from llm_grop.geometry.motion import leg_duration_s
from llm_grop.geometry.obstacles import Obstacles
from llm_grop.planning.feasibility import ParametricFeasibility
from llm_grop.simulation.registry import create_simulator
from llm_grop.world.robot import Robot

PROFILES = Path(__file__).resolve().parents[1] / "src/llm_grop/data/feasibility.yaml"
KINDS = ("navigate", "pick", "place")


def episode(job: tuple[str, int, int, str, str, str | None]) -> dict[str, Any] | None:
    """One Task 8 episode's measurements (plain data, for the parent process); ``None``
    when nothing feasible was found to execute."""
    method, chairs, seed, simulator, feasibility, truth = job
    sim = create_simulator(simulator, truth=truth)
    t0 = time.perf_counter()
    try:
        r = run(task=8, seed=seed, llm=replay_llm(), method=method, chairs=chairs,
                simulator=sim, feasibility=feasibility)
    except Infeasible as e:
        print(f"{method}, {chairs} chairs, seed {seed}: skipped, {e}", flush=True)
        return None
    wall = time.perf_counter() - t0
    scene, robot = r.scene, r.scene.robot
    obstacles = Obstacles(scene, include_chairs=True)
    targets = {p.name: scene.table_to_room(p.x, p.y) for p in r.plan.configuration}
    attempts = []
    for s in r.execution.steps:
        if s.tray:
            # A load onto the tray or an unload from it: timed, not part of the reach fit.
            attempts.append({"action": "load" if s.action == "place" else "unload",
                             "x": math.nan, "ok": s.ok, "attempt": s.attempt,
                             "reason": s.reason, "duration_s": s.duration_s,
                             "object": s.object, "arrival_m": None, "goal": None})
            continue
        if s.action == "navigate" and s.goal is not None:
            x = float(obstacles.clearance([(s.goal.x, s.goal.y)])[0]) - robot.base_radius_m
        elif s.standing is not None and s.reason != "disturbed":
            if s.action == "pick":
                if s.pose is None:
                    continue  # a 2D pick beyond reach says not where the object lay
                ox, oy = s.pose[0], s.pose[1]
            else:
                t = targets[s.object or ""]
                ox, oy = t.x, t.y
            x = math.hypot(ox - s.standing.x, oy - s.standing.y)
        else:
            continue
        attempts.append({"action": s.action, "x": x, "ok": s.ok, "attempt": s.attempt,
                         "reason": s.reason, "duration_s": s.duration_s,
                         "object": s.object, "arrival_m": s.arrival_error_m,
                         "goal": [s.goal.x, s.goal.y] if s.goal is not None else None})
    planned_legs = [(st.duration_s, leg_duration_s(_prev(r.plan.steps, k, scene), st.goal,
                                                    st.path, robot), st.goal.x, st.goal.y,
                     st.object)
                    for k, st in enumerate(r.plan.steps) if st.action == "navigate"]
    return {"method": method, "chairs": chairs, "seed": seed, "wall_s": wall,
            "success": r.success, "all_placed": not r.execution.unplaced,
            "failures": sum(not s.ok and s.reason not in (None, "disturbed")
                            for s in r.execution.steps),
            "reasons": Counter(s.reason for s in r.execution.steps
                               if not s.ok and s.reason is not None),
            "tipped": [s.object for s in r.execution.steps if s.reason == "tipped"],
            "execution_s": r.execution.execution_time_s,
            "expected_s": r.plan.expected_duration_s if r.plan.expected_duration_s is not None
            else sum(st.duration_s for st in r.plan.steps),
            "feasibility": r.plan.feasibility,
            "predicted": {k: [st.success_p for st in r.plan.steps if st.action == k]
                          for k in KINDS},
            "planned_legs": planned_legs, "attempts": attempts}


def _prev(steps: Any, k: int, scene: Any) -> Any:
    """Where the robot stands before plan step ``k``: the last goal or standing pose."""
    for st in reversed(steps[:k]):
        if st.goal is not None:
            return st.goal
    return scene.robot_start


def report(rows: list[dict[str, Any]]) -> None:
    """The figures per method and chair count."""
    groups: dict[tuple[str, int], list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        groups[(r["method"], r["chairs"])].append(r)
    print("| method | chairs | all placed | failed attempts / episode (by reason) | "
          "arrival error median / p95 (cm) | execution (s) | wall / episode (s) |")
    print("| --- | ---: | ---: | --- | ---: | ---: | ---: |")
    for (method, chairs), rs in sorted(groups.items()):
        n = len(rs)
        reasons: Counter[str] = Counter()
        for r in rs:
            reasons.update({k: v for k, v in r["reasons"].items() if k != "disturbed"})
        by = ", ".join(f"{k} {v / n:.2f}" for k, v in reasons.most_common())
        arrivals = [a["arrival_m"] for r in rs for a in r["attempts"]
                    if a["action"] == "navigate" and a["ok"] and a["arrival_m"] is not None]
        med, p95 = median_p95(arrivals) if arrivals else (math.nan, math.nan)
        print(f"| {method} | {chairs} | {sum(r['all_placed'] for r in rs) / n:.0%} | "
              f"{sum(r['failures'] for r in rs) / n:.2f} ({by or 'none'}) | "
              f"{100 * med:.1f} / {100 * p95:.1f} | "
              f"{statistics.fmean(r['execution_s'] for r in rs):.1f} | "
              f"{statistics.median(r['wall_s'] for r in rs):.1f} |")
    print()
    print("| method | chairs | " + " | ".join(f"{k} first attempt" for k in KINDS)
          + " | P(no failed attempt) | execution time (s) |")
    print("| --- | ---: | " + " | ".join("---:" for _ in KINDS) + " | ---: | ---: |")
    for (method, chairs), rs in sorted(groups.items()):
        cells = []
        for k in KINDS:
            pred = [p for r in rs for p in r["predicted"][k]]
            meas = [a["ok"] for r in rs for a in r["attempts"]
                    if a["action"] == k and a["attempt"] == 1]
            cells.append(f"{statistics.fmean(pred):.2f} / {statistics.fmean(meas):.2f}")
        whole = (f"{statistics.fmean(r['feasibility'] for r in rs):.2f} / "
                 f"{statistics.fmean(r['failures'] == 0 for r in rs):.2f}")
        exp = statistics.fmean(r["expected_s"] for r in rs)
        got = statistics.fmean(r["execution_s"] for r in rs)
        print(f"| {method} | {chairs} | " + " | ".join(cells) +
              f" | {whole} | {exp:.1f} / {got:.1f} ({100 * (exp / got - 1):+.1f} %) |")
    print("(each cell: predicted / measured)")


def fitted(rows: list[dict[str, Any]]) -> dict[str, float | None]:
    """The profile that makes every attempt most likely, and the measured durations."""
    attempts = [a for r in rows for a in r["attempts"]]

    def samples(action: str, only_first: bool) -> list[Sample]:
        # A drive that dropped what it carried failed the grasp, not the drive.
        return [Sample(a["x"], a["ok"]) for a in attempts
                if a["action"] == action and (a["attempt"] == 1 or not only_first)
                and not (action == "navigate" and a["reason"] == "fell")]

    robot = Robot()
    # The reach curve's shape from every attempt (the arm's reach does not change on a
    # retry) ...
    shape = fit(samples("pick", False), samples("navigate", True), robot,
                places=samples("place", False))
    # ... and its tops from first attempts, which are what the belief predicts: a retry
    # follows a slip or a bump, which the plan does not plan for.
    tops = [_top(samples(action, True), shape, robot, action == "place")
            for action in ("pick", "place")]
    model = replace(shape, manip_max=tops[0], place_max=tops[1])
    nav, picks, places = (samples(a, True) for a in KINDS)

    def mean(values: list[float]) -> float:
        return round(statistics.fmean(values), 2) if values else 0.0

    pick_s = [a["duration_s"] for a in attempts if a["action"] == "pick" and a["ok"]]
    place_s = [a["duration_s"] for a in attempts if a["action"] == "place" and a["ok"]]
    # The overhead of a drive: what it took beyond its path and turns at full speed, over
    # the planned legs driven as planned (a leg's first attempt at its own goal).
    overhead = [a["duration_s"] - leg[1] for r in rows for a, leg in _as_planned(r)]
    leg_s, pick_mean, place_mean = max(0.0, mean(overhead)), mean(pick_s), mean(place_s)
    # What a failed attempt costs, its recovery included (drives back, re-grasps, putting
    # back what it disturbed): each episode's time beyond its plan when nothing fails,
    # shared among its failed attempts. Like the overhead, from the episodes that kept
    # their goals: the latest runs, planned with the latest belief, whose mix of failures
    # the profile will meet (an early fit's plans fail far more, and differently).
    timed = [r for r in rows if _as_planned(r)] or rows
    extra = sum(r["execution_s"] - sum(leg[1] + leg_s for leg in r["planned_legs"])
                - len(r["predicted"]["pick"]) * pick_mean
                - len(r["predicted"]["place"]) * place_mean for r in timed)
    failures = sum(r["failures"] for r in timed)
    kinds: Counter[str] = Counter(o for r in rows for o in r["tipped"])
    placed: Counter[str] = Counter(a["object"] for a in attempts if a["action"] == "place")
    print("tipped after a place, by object: " + (", ".join(
        f"{k} {kinds[k]} of {placed[k]}" for k in sorted(placed)) or "none"))
    print(f"fit from {len(nav)} drives, {len(picks)} picks and {len(places)} places")
    # Loads and unloads (runs with --capacity above 1): the median of every attempt,
    # failed ones included, as benchmarks/tray_place_setting.py measures them.
    tray_s = {k: [a["duration_s"] for a in attempts if a["action"] == k]
              for k in ("load", "unload")}
    for k, v in tray_s.items():
        if v:
            print(f"{k}s: n {len(v)}, median {statistics.median(v):.2f} s")
    return {"nav_max": model.nav_max, "nav_mid_m": model.nav_mid_m,
            "nav_scale_m": model.nav_scale_m, "manip_max": model.manip_max,
            "knee": model.knee, "reach_max_m": model.reach_max_m,
            "place_max": model.place_max,
            "pick_time_s": pick_mean, "place_time_s": place_mean, "leg_overhead_s": leg_s,
            "failed_attempt_s": round(max(0.0, extra / failures), 2) if failures else 0.0,
            # None (no loads measured): --write keeps the profile's own.
            "load_time_s": round(statistics.median(tray_s["load"]), 2)
            if tray_s["load"] else None,
            "unload_time_s": round(statistics.median(tray_s["unload"]), 2)
            if tray_s["unload"] else None}


def _as_planned(row: dict[str, Any]) -> list[tuple[dict[str, Any], Any]]:
    """The episode's successful drives that drove a planned leg as planned, each with its
    leg: in plan order, the next first attempt at the leg's goal for the leg's object."""
    drives = [a for a in row["attempts"] if a["action"] == "navigate"]
    if any(a.get("goal") is None for a in drives):
        return []  # saved by an earlier version, which did not keep the goals
    out, k = [], 0
    for leg in row["planned_legs"]:
        for j in range(k, len(drives)):
            a = drives[j]
            if a["attempt"] == 1 and math.dist(a["goal"], leg[2:4]) < 1e-6 \
                    and (len(leg) < 5 or a["object"] == leg[4]):
                if a["ok"]:
                    out.append((a, leg))
                k = j + 1
                break
    return out


def _top(observed: list[Sample], shape: ParametricFeasibility, robot: Robot, place: bool
         ) -> float:
    """The curve's top that makes ``observed`` most likely, its shape kept."""
    x = np.array([o.x for o in observed])
    y = np.array([o.ok for o in observed], float)

    def nll(top: float) -> float:
        m = replace(shape, manip_max=top, place_max=top)
        q = likelihood_p(m.placing(x, robot) if place else m.manipulation(x, robot))
        return float(-np.sum(y * np.log(q) + (1 - y) * np.log(1 - q)))

    return round(float(minimize_scalar(nll, bounds=(0.05, 1.0), method="bounded").x), 4)


def write(profile: dict[str, float | None], description: str) -> None:
    """Replace the ``mujoco`` profile in the packaged file, keeping everything else and
    the profile's own lines (with the comments above them) for keys the fit leaves
    ``None`` (the loads' and unloads' seconds of runs without a tray)."""
    text = PROFILES.read_text(encoding="utf-8")
    old = re.search(r"^mujoco:\n((?:  .*\n)*)", text, flags=re.M)
    kept, comments = [], []
    for line in (old.group(1).splitlines(keepends=True) if old else []):
        if line.lstrip().startswith("#"):
            comments.append(line)
            continue
        key = line.split(":")[0].strip()
        if key in ("load_time_s", "unload_time_s") and profile.get(key) is None:
            kept += comments + [line]
        comments = []
    block = "mujoco:\n" + f"  description: {description}\n" + "".join(
        f"  {k}: {v}\n" for k, v in profile.items() if v is not None) + "".join(kept)
    new, n = re.subn(r"^mujoco:\n(?:  .*\n)*", block, text, flags=re.M)
    if n != 1:
        raise SystemExit(f"{PROFILES}: no mujoco profile to replace")
    PROFILES.write_text(new, encoding="utf-8")
    print(f"wrote profile mujoco to {PROFILES}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--simulator", default="mujoco")
    ap.add_argument("--truth", default=None)
    ap.add_argument("--feasibility", default="default")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=0,
                    help="run seeds first-seed .. first-seed + seeds - 1")
    ap.add_argument("--methods", default="grop,llm-grop")
    ap.add_argument("--chairs", default="1,4")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--fit", action="store_true")
    ap.add_argument("--write", action="store_true")
    ap.add_argument("--save", type=Path, help="write the episodes' measurements here (JSON)")
    ap.add_argument("--also", type=Path, nargs="*", default=[],
                    help="fit also to episodes saved by earlier runs (--save)")
    args = parse_args(ap, {"simulator": "kinematic2d", "seeds": 1, "methods": "llm-grop",
                           "chairs": "1", "workers": 1, "fit": True})
    jobs = [(m, int(c), s, args.simulator, args.feasibility, args.truth)
            for m in args.methods.split(",") for c in args.chairs.split(",")
            for s in range(args.first_seed, args.first_seed + args.seeds)]
    t0 = time.perf_counter()
    if args.seeds == 0:
        rows: list[dict[str, Any]] = []  # fit to saved episodes alone (--also)
    else:
        with multiprocessing.get_context("spawn").Pool(args.workers) as pool:
            rows = [r for r in pool.map(episode, jobs, chunksize=1) if r is not None]
    if args.save:
        args.save.write_text(json.dumps(rows), encoding="utf-8")
    print(f"{len(rows)} Task 8 episodes on {args.simulator}"
          f"{' (truth ' + args.truth + ')' if args.truth else ''}, belief "
          f"{args.feasibility}, {time.perf_counter() - t0:.0f} s wall on {args.workers} "
          f"workers")
    earlier = [r for path in args.also for r in json.loads(path.read_text("utf-8"))]
    if rows or earlier:
        report(rows or earlier)  # with --seeds 0, the saved episodes' figures
    if args.fit or args.write:
        profile = fitted(rows + earlier)
        print("fitted: " + ", ".join(f"{k} {v}" for k, v in profile.items()))
        if args.write:
            n = len(rows) + len(earlier)
            write(profile, f"fitted in MuJoCo by benchmarks/fit_profile.py ({n} Task 8 "
                           f"episodes through the executive, GROP and LLM-GROP, 1 and 4 "
                           f"chairs, planned with the default belief and earlier fits)")


if __name__ == "__main__":
    main()
