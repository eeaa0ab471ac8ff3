"""Calibrate the planner's feasibility model in MuJoCo and fit the ``mujoco`` profile.

Measures manipulation success against planned reach and navigation success against goal
clearance in the 3D world (with its arrival noise), fits the parametric model by maximum
likelihood, and prints measured rates beside the ``default`` profile's and the fitted
model's predictions. ``--write`` stores the fit in src/llm_grop/data/feasibility.yaml.
Run: .venv/bin/python benchmarks/calibrate_mujoco.py [--trials 24] [--write] [--quick]
"""

from __future__ import annotations

import argparse
import re
import time
from pathlib import Path

from common import parse_args
from rich.console import Console
from rich.progress import Progress
from rich.table import Table

from llm_grop.experiment.calibration import (
    fit,
    measure_manipulation,
    measure_navigation,
    rates,
)
from llm_grop.planning.feasibility import feasibility_profile
from llm_grop.simulation.mujoco.simulator import MujocoSimulator
from llm_grop.world.robot import Robot

PROFILES = Path(__file__).resolve().parents[1] / "src/llm_grop/data/feasibility.yaml"
REACHES = [0.40, 0.50, 0.60, 0.70, 0.75, 0.80, 0.85, 0.90, 0.95, 1.00, 1.05, 1.10, 1.15,
           1.20, 1.30]
CLEARANCES = [0.0, 0.02, 0.04, 0.06, 0.08, 0.10, 0.15, 0.20, 0.30, 0.45]
#: The reaches and clearances of ``--quick``: three spread over each range.
QUICK_REACHES, QUICK_CLEARANCES = REACHES[::7], CLEARANCES[::4]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=24, help="episodes per reach and clearance")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--write", action="store_true", help="store the fit as profile mujoco")
    args = parse_args(ap, {"trials": 1})
    reaches, clearances = (QUICK_REACHES, QUICK_CLEARANCES) if args.quick else (
        REACHES, CLEARANCES)
    sim = MujocoSimulator()
    console = Console()
    t0 = time.perf_counter()
    with Progress(console=console) as progress:
        bar = progress.add_task("manipulation (attempts)", total=None)
        manip = measure_manipulation(sim, reaches, args.trials, args.seed,
                                     on_sample=lambda s: progress.advance(bar))
        bar = progress.add_task("navigation", total=len(clearances) * args.trials)
        nav = measure_navigation(sim, clearances, args.trials, args.seed,
                                 on_sample=lambda s: progress.advance(bar))
    fitted = fit(manip, nav)
    default = feasibility_profile("default")
    robot = Robot()
    console.print(f"{len(manip)} manipulation and {len(nav)} navigation attempts in "
                  f"{time.perf_counter() - t0:.0f} s")
    for title, samples, label, predict in (
            ("Manipulation success against planned reach", manip, "reach (m)",
             lambda m, x: float(m.manipulation(x, robot))),
            ("Navigation success against goal clearance", nav, "clearance (m)",
             lambda m, x: float(m.navigation(x)))):
        table = Table(title=title)
        for col in (label, "attempts", "measured", "default predicts", "fitted predicts"):
            table.add_column(col, justify="right")
        for x, (ok, n) in rates(samples).items():
            table.add_row(f"{x:.2f}", str(n), f"{ok / n:.2f}", f"{predict(default, x):.2f}",
                          f"{predict(fitted, x):.2f}")
        console.print(table)
    console.print(f"fitted: nav_max {fitted.nav_max}, nav_mid_m {fitted.nav_mid_m}, "
                  f"nav_scale_m {fitted.nav_scale_m}, manip_max {fitted.manip_max}, "
                  f"knee {fitted.knee}, reach_max_m {fitted.reach_max_m}")
    if args.write:
        write_profile(fitted, len(manip), len(nav), args.trials)
        console.print(f"wrote profile mujoco to {PROFILES}")


def write_profile(m: object, n_manip: int, n_nav: int, trials: int) -> None:
    """Replace the ``mujoco`` block of the profiles file (comments elsewhere are kept)."""
    text = PROFILES.read_text(encoding="utf-8")
    text = re.sub(r"\nmujoco:\n(?:  .*\n)*", "\n", text).rstrip("\n") + "\n"
    fields = ("nav_max", "nav_mid_m", "nav_scale_m", "manip_max", "knee", "reach_max_m")
    block = [
        "mujoco:",
        f"  description: fitted in MuJoCo by benchmarks/calibrate_mujoco.py --trials {trials} "
        f"({n_manip} pick and place attempts, {n_nav} drives)",
        *(f"  {f}: {getattr(m, f)}" for f in fields),
    ]
    PROFILES.write_text(text + "\n".join(block) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
