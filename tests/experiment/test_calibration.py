"""Calibrating the planner's belief against a simulator, and the feasibility profiles."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from llm_grop.cli import main
from llm_grop.errors import BadInput
from llm_grop.experiment.calibration import (
    Sample,
    fit,
    measure_manipulation,
    measure_navigation,
    rates,
)
from llm_grop.planning.feasibility import (
    ParametricFeasibility,
    feasibility_profile,
    profile_names,
)
from llm_grop.simulation.kinematic2d import Kinematic2D
from llm_grop.simulation.mujoco.simulator import MujocoSimulator
from llm_grop.world.robot import Robot


def test_fit_recovers_the_model_that_drew_the_samples() -> None:
    truth = ParametricFeasibility(nav_max=0.9, nav_mid_m=0.05, nav_scale_m=0.03,
                                  manip_max=0.9, knee=0.75, reach_max_m=1.1)
    rng = np.random.default_rng(0)
    robot = Robot()
    reaches = np.repeat(np.linspace(0.4, 1.2, 17), 150)
    clearances = np.repeat(np.linspace(0.0, 0.4, 17), 150)
    manip = [Sample(float(x), bool(rng.random() < truth.manipulation(x, robot)))
             for x in reaches]
    nav = [Sample(float(x), bool(rng.random() < truth.navigation(x))) for x in clearances]
    got = fit(manip, nav, robot)
    assert got.nav_max == pytest.approx(0.9, abs=0.05)
    assert got.nav_mid_m == pytest.approx(0.05, abs=0.02)
    assert got.manip_max == pytest.approx(0.9, abs=0.04)
    assert got.reach_max_m == pytest.approx(1.1, abs=0.05)
    assert got.knee * got.reach_max_m == pytest.approx(0.825, abs=0.08)


def test_fit_recovers_a_place_curve_of_its_own() -> None:
    truth = ParametricFeasibility(manip_max=0.98, knee=0.75, reach_max_m=1.0, place_max=0.8)
    rng = np.random.default_rng(1)
    robot = Robot()
    reaches = np.repeat(np.linspace(0.3, 1.05, 16), 200)
    picks = [Sample(float(x), bool(rng.random() < truth.manipulation(x, robot)))
             for x in reaches]
    places = [Sample(float(x), bool(rng.random() < truth.placing(x, robot))) for x in reaches]
    nav = [Sample(0.1, True)] * 10
    got = fit(picks, nav, robot, places=places)
    assert got.manip_max == pytest.approx(0.98, abs=0.03)
    assert got.place_max == pytest.approx(0.8, abs=0.04)
    assert got.reach_max_m == pytest.approx(1.0, abs=0.05)


@pytest.mark.parametrize("simulator", [Kinematic2D(), MujocoSimulator()],
                         ids=["kinematic2d", "mujoco"])
def test_measurements_run_through_sessions(simulator) -> None:  # type: ignore[no-untyped-def]
    manip = measure_manipulation(simulator, [0.55, 1.3], trials=2)
    by_reach = rates(manip)
    assert set(by_reach) <= {0.55, 1.3} and 0.55 in by_reach
    ok, n = by_reach[0.55]
    assert ok >= 1 and n >= 2  # well within reach: picked and put back
    nav = measure_navigation(simulator, [0.3], trials=2)
    assert [s.x for s in nav] == [0.3, 0.3]


def test_profiles_are_packaged_and_checked() -> None:
    assert {"default", "mujoco"} <= set(profile_names())
    assert feasibility_profile("default") == ParametricFeasibility()
    fitted = feasibility_profile("mujoco")
    assert fitted.reach_max_m is not None and fitted.reach_max_m > Robot().reach_max_m
    with pytest.raises(BadInput, match="unknown profile 'nope'"):
        feasibility_profile("nope")


def test_run_names_its_profile(tmp_path: Path) -> None:
    out = tmp_path / "run.json"
    assert main(["run", "a dinner fork", "--method", "grop", "--feasibility", "mujoco",
                 "--json", str(out), "-q"]) == 0
    assert json.loads(out.read_text())["feasibility"] == "mujoco"
    # auto, the default: the profile fitted to the simulator that executes.
    assert main(["run", "a dinner fork", "--method", "grop", "--json", str(out), "-q"]) == 0
    assert json.loads(out.read_text())["feasibility"] == "default"
    assert main(["run", "a dinner fork", "--method", "grop", "--truth", "mujoco",
                 "--json", str(out), "-q"]) == 0
    assert json.loads(out.read_text())["feasibility"] == "mujoco"


def test_auto_follows_the_simulator() -> None:
    """``auto`` is resolved by the simulator's declared fitted profile, so the 3D world
    plans with what was measured there; an explicit profile still wins."""
    from llm_grop.assembly import resolve_feasibility
    from llm_grop.settings import RunSettings
    from llm_grop.simulation.mujoco.simulator import MujocoSimulator

    assert RunSettings().feasibility == "auto"
    assert resolve_feasibility(RunSettings(simulator="mujoco")).feasibility == "mujoco"
    assert resolve_feasibility(RunSettings(truth="mujoco")).feasibility == "mujoco"
    assert resolve_feasibility(RunSettings()).feasibility == "default"
    assert resolve_feasibility(RunSettings(), MujocoSimulator()).feasibility == "mujoco"
    named = RunSettings(simulator="mujoco", feasibility="default")
    assert resolve_feasibility(named).feasibility == "default"


def test_an_unknown_profile_names_auto_among_the_choices() -> None:
    from llm_grop.assembly import resolve_feasibility
    from llm_grop.settings import RunSettings

    with pytest.raises(BadInput, match="unknown profile 'nope'; choose from auto, default"):
        resolve_feasibility(RunSettings(feasibility="nope"))
