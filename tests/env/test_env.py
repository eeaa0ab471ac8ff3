"""The Gymnasium environment over both simulators."""

from __future__ import annotations

import numpy as np
import pytest

from llm_grop.env.dining import NAVIGATE, PICK, PLACE, DiningRoomEnv
from llm_grop.errors import BadInput
from llm_grop.planning.grop import build_plan, choose
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.utility import PlanningContext
from llm_grop.simulation.mujoco.simulator import MujocoOptions, MujocoSimulator
from llm_grop.world.arrangement import Configuration, Placement

SIMULATORS = ["kinematic2d", "mujoco"]


@pytest.mark.parametrize("simulator", ["kinematic2d",
                                       MujocoSimulator(MujocoOptions(nav_noise_var_m2=0.0))],
                         ids=SIMULATORS)
def test_a_plan_driven_through_the_environment_sets_the_table(simulator) -> None:  # type: ignore[no-untyped-def]
    env = DiningRoomEnv(["dinner plate"], simulator=simulator, chairs=0)
    obs, _ = env.reset(seed=2)
    assert obs["held"] == 1 and obs["on_table"].tolist() == [0]
    scene = env.episode_scene
    assert scene is not None
    ctx = PlanningContext(scene, env.items)
    plate = env.items[0].spec
    target = Placement("dinner plate", 0.0, -0.1, 0.0, plate.shape, plate.size, None,
                       plate.name, plate.height)
    plan = build_plan(ctx, choose(ctx, [Configuration((target,))]),
                      Navigator(scene, scene.robot.base_radius_m), seed=2, configurations=1)
    total, terminated = 0.0, False
    for step in plan.steps:
        if step.action == "navigate":
            assert step.goal is not None
            action = {"action": NAVIGATE, "object": 0,
                      "pose": env.pose_action(NAVIGATE, *step.goal.as_list())}
        elif step.action == "pick":
            action = {"action": PICK, "object": 0, "pose": np.zeros(3, np.float32)}
        else:
            action = {"action": PLACE, "object": 0,
                      "pose": env.pose_action(PLACE, target.x, target.y, target.yaw)}
        for _ in range(3):  # an agent retries a failed action, as the simulators do
            obs, reward, terminated, truncated, info = env.step(action)
            total += reward
            assert not truncated
            if info["ok"]:
                break
        assert info["ok"], info
    assert terminated and obs["on_table"].tolist() == [1] and obs["held"] == 1
    assert 0.0 < total < 1.0  # +1 for the plate, minus its time


def test_actions_that_cannot_be_done_fail_without_ending_the_episode() -> None:
    env = DiningRoomEnv(["dinner fork"], chairs=0)
    env.reset(seed=1)
    _, _, terminated, _, info = env.step({"action": PLACE, "object": 0,
                                          "pose": np.zeros(3, np.float32)})
    assert not info["ok"] and "does not hold" in info["note"] and not terminated
    _, _, _, _, info = env.step({"action": PICK, "object": 0, "pose": np.zeros(3, np.float32)})
    assert not info["ok"]  # out of reach from the start
    _, _, _, _, info = env.step({"action": NAVIGATE, "object": 0,
                                 "pose": env.pose_action(NAVIGATE, 4.0, 3.0, 0.0)})
    assert not info["ok"] and info["note"] == "no path"  # inside the dining table


def test_same_seed_same_episode() -> None:
    env = DiningRoomEnv(task=8)
    a, _ = env.reset(seed=7)
    b, _ = env.reset(seed=7)
    c, _ = env.reset(seed=8)
    assert all(np.array_equal(a[k], b[k]) for k in a)
    assert not np.array_equal(a["objects"], c["objects"])


def test_bad_settings_are_bad_input() -> None:
    with pytest.raises(BadInput, match="render_mode"):
        DiningRoomEnv(render_mode="human")
    with pytest.raises(BadInput, match="unknown"):
        DiningRoomEnv(simulator="nope")


def test_stacking_through_the_environment() -> None:
    env = DiningRoomEnv(["bread plate", "bread"], chairs=0)
    env.reset(seed=4)
    scene = env.episode_scene
    assert scene is not None
    specs = {i.name: i.spec for i in env.items}
    targets = tuple(Placement(n, 0.0, -0.1, 0.0, specs[n].shape, specs[n].size,
                              "bread plate" if n == "bread" else None, n, specs[n].height)
                    for n in ("bread plate", "bread"))
    ctx = PlanningContext(scene, env.items)
    plan = build_plan(ctx, choose(ctx, [Configuration(targets)]),
                      Navigator(scene, scene.robot.base_radius_m), seed=4, configurations=1)
    index = {n: k for k, n in enumerate(env.names)}
    by_name = {t.name: t for t in targets}
    for step in plan.steps:
        k = index[step.object or ""]
        if step.action == "navigate":
            assert step.goal is not None
            action = {"action": NAVIGATE, "object": k,
                      "pose": env.pose_action(NAVIGATE, *step.goal.as_list())}
        elif step.action == "pick":
            action = {"action": PICK, "object": k, "pose": np.zeros(3, np.float32)}
        else:
            t = by_name[step.object or ""]
            action = {"action": PLACE, "object": k, "on": index.get(t.on or "", 2),
                      "pose": env.pose_action(PLACE, t.x, t.y, t.yaw)}
        for _ in range(3):
            *_, info = env.step(action)
            if info["ok"]:
                break
        assert info["ok"], info
    assert env.session is not None
    states = env.session.objects()
    assert states["bread"].on == "bread plate" and states["bread"].tilt_rad == 0.0


def test_actions_outside_the_space_are_refused() -> None:
    env = DiningRoomEnv(["bread plate", "bread"], chairs=0)
    env.reset(seed=4)
    with pytest.raises(ValueError, match="not in the action space"):
        env.step({"action": 3, "object": 0, "pose": np.zeros(3, np.float32)})
    with pytest.raises(ValueError, match="not in the action space"):
        env.step({"action": PLACE, "object": 0, "on": 5, "pose": np.zeros(3, np.float32)})
