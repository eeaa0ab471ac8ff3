"""The environment keeps Gymnasium's conventions: ``check_env`` without a warning,
``TimeLimit`` truncation, ``rgb_array`` frames, bounded spaces and a normalised action."""

from __future__ import annotations

import math
import warnings
from dataclasses import replace
from typing import Any

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.wrappers import TimeLimit

from llm_grop.env import ENV_ID, MAX_EPISODE_STEPS
from llm_grop.env.dining import NAVIGATE, PICK, PLACE, DiningRoomEnv
from llm_grop.errors import BadInput
from llm_grop.files.scene_file import load_scene, set_target_top
from llm_grop.world.table import Table

SIMULATORS = ["kinematic2d", "mujoco"]
#: A pick of the fork from the start, always out of reach (seed 1, no chairs): an action
#: that changes nothing, so an episode of them never terminates.
FUTILE_PICK = {"action": PICK, "object": 0, "pose": np.zeros(3, np.float32)}


@pytest.mark.parametrize("simulator", SIMULATORS)
def test_check_env_passes_with_warnings_as_errors(simulator: str) -> None:
    env = gymnasium.make(ENV_ID, simulator=simulator, render_mode="rgb_array",
                         objects=["dinner fork", "mug"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped, skip_render_check=False)


def test_made_episodes_are_truncated_by_time_limit() -> None:
    env = gymnasium.make(ENV_ID, objects=["dinner fork"], chairs=0)
    assert env.spec is not None and env.spec.max_episode_steps == MAX_EPISODE_STEPS == 60
    assert _wrapper(env, TimeLimit) is not None
    assert env.unwrapped.max_steps is None  # type: ignore[attr-defined]  # no second limit
    env.reset(seed=1)
    for _ in range(MAX_EPISODE_STEPS - 1):
        _, _, terminated, truncated, info = env.step(FUTILE_PICK)
        assert not info["ok"] and not terminated and not truncated
    _, _, terminated, truncated, _ = env.step(FUTILE_PICK)
    assert truncated and not terminated


def test_the_limit_can_be_changed_and_a_direct_env_keeps_max_steps() -> None:
    env = gymnasium.make(ENV_ID, objects=["dinner fork"], chairs=0, max_episode_steps=3)
    env.reset(seed=1)
    assert [env.step(FUTILE_PICK)[3] for _ in range(3)] == [False, False, True]
    direct = DiningRoomEnv(["dinner fork"], chairs=0, max_steps=2)
    direct.reset(seed=1)
    assert [direct.step(FUTILE_PICK)[3] for _ in range(2)] == [False, True]
    unlimited = DiningRoomEnv(["dinner fork"], chairs=0)
    unlimited.reset(seed=1)
    assert not any(unlimited.step(FUTILE_PICK)[3] for _ in range(MAX_EPISODE_STEPS + 1))
    with pytest.raises(BadInput, match="max_steps.*at least 1"):
        DiningRoomEnv(["dinner fork"], max_steps=0)


@pytest.mark.parametrize("simulator", SIMULATORS)
def test_rgb_array_gives_frames(simulator: str) -> None:
    env = gymnasium.make(ENV_ID, simulator=simulator, render_mode="rgb_array",
                         objects=["dinner fork", "mug"], image_size=(96, 64))
    assert env.metadata["render_modes"] == ["rgb_array"] and env.metadata["render_fps"] > 0
    obs, _ = env.reset(seed=5)
    assert "image" not in obs
    frame = env.render()
    assert isinstance(frame, np.ndarray)
    assert frame.shape == (64, 96, 3) and frame.dtype == np.uint8
    assert frame.std() > 5 and len(np.unique(frame.reshape(-1, 3), axis=0)) > 3
    goal = env.unwrapped.pose_action(NAVIGATE, 1.6, 1.0, 0.0)  # type: ignore[attr-defined]
    env.step({"action": NAVIGATE, "object": 0, "pose": goal})
    assert not np.array_equal(env.render(), frame)  # the robot moved
    plain = gymnasium.make(ENV_ID, simulator=simulator, objects=["mug"])
    plain.reset(seed=5)
    assert plain.render() is None


def test_rgb_array_list_collects_a_frame_per_step() -> None:
    env = gymnasium.make(ENV_ID, render_mode="rgb_array_list", objects=["dinner fork"],
                         chairs=0)
    env.reset(seed=1)
    env.step(FUTILE_PICK)
    env.step(FUTILE_PICK)
    frames = env.render()
    assert len(frames) == 3 and all(f.shape == (120, 160, 3) for f in frames)


@pytest.mark.parametrize("simulator", SIMULATORS)
def test_camera_is_a_deprecated_alias_of_render(simulator: str) -> None:
    with pytest.warns(DeprecationWarning) as record:
        env = gymnasium.make(ENV_ID, simulator=simulator, camera=True,
                             render_mode="rgb_array", objects=["dinner fork", "mug"])
    (warning,) = [w for w in record if "camera" in str(w.message)]
    message = str(warning.message)
    assert "render_mode='rgb_array'" in message and "env.render()" in message
    assert "removed in the next minor release" in message
    assert warning.filename == __file__  # it points at the caller's line
    obs, _ = env.reset(seed=5)
    assert obs["image"].shape == (120, 160, 3) and obs["image"].dtype == np.uint8
    assert obs["image"].std() > 5 and env.observation_space.contains(obs)
    assert np.array_equal(obs["image"], env.render())
    with pytest.warns(DeprecationWarning, match="camera=True"):
        DiningRoomEnv(["mug"], camera=True)


@pytest.mark.parametrize(("simulator", "steps"), [("kinematic2d", MAX_EPISODE_STEPS),
                                                  ("mujoco", 6)])
def test_observations_stay_in_their_spaces_under_a_random_policy(simulator: str,
                                                                 steps: int) -> None:
    env = gymnasium.make(ENV_ID, simulator=simulator, task=8, chairs=2,
                         max_episode_steps=steps)
    env.action_space.seed(11)
    obs, _ = env.reset(seed=11)
    space = env.observation_space
    _assert_inside(space, obs)
    _assert_readings_inside(env)
    done, count = False, 0
    while not done:
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        _assert_inside(space, obs)
        _assert_readings_inside(env)
        assert math.isfinite(reward)
        done, count = terminated or truncated, count + 1
    assert count == steps and truncated


def test_bounds_come_from_the_scene() -> None:
    scene = set_target_top(load_scene(), Table(1.2, 1.2, "circle"))
    scene = replace(scene, width=9.0)
    env = DiningRoomEnv(["dinner plate", "mug"], scene=scene, chairs=1)
    robot = env.observation_space["robot"]
    assert robot.low.tolist() == pytest.approx([0.0, 0.0, -math.pi])
    assert robot.high.tolist() == pytest.approx([9.0, 6.0, math.pi])
    objects = env.observation_space["objects"]
    assert objects.shape == (2, 4) and objects.high[0, :2].tolist() == [9.0, 6.0]
    heights = env.items[0].spec.height + env.items[1].spec.height
    tallest = max(t.height for t in scene.tables)
    assert objects.high[0, 2] == pytest.approx(tallest + heights + scene.robot.reach_max_m)
    assert env.observation_space["chairs"].high[0, :2].tolist() == [9.0, 6.0]
    assert env.action_space["pose"].low.tolist() == [-1.0, -1.0, -1.0]
    assert env.action_space["pose"].high.tolist() == [1.0, 1.0, 1.0]
    # A normalised pose spans the room's floor for navigate, the table's top for place.
    assert env.pose_action(NAVIGATE, 9.0, 6.0, math.pi).tolist() == [1.0, 1.0, 1.0]
    assert env.pose_action(NAVIGATE, 0.0, 0.0, -math.pi).tolist() == [-1.0, -1.0, -1.0]
    assert env.pose_action(NAVIGATE, 4.5, 3.0, 0.0).tolist() == [0.0, 0.0, 0.0]
    assert env.pose_action(PLACE, 0.6, -0.6, math.pi / 2).tolist() == [1.0, -1.0, 0.5]
    assert env.pose_frames[PLACE].to_physical(np.array([0.5, 0.0, -1.0])) == \
        pytest.approx((0.3, 0.0, -math.pi))
    with pytest.raises(BadInput, match=r"x: 9.5 m is outside the room's \[0, 9\] m"):
        env.pose_action(NAVIGATE, 9.5, 3.0, 0.0)
    with pytest.raises(ValueError, match="outside the target table's top"):
        env.pose_action(PLACE, 0.0, 0.7, 0.0)
    with pytest.raises(BadInput, match="action.*0 .navigate., 1 .pick. or 2 .place."):
        env.pose_action(5, 0.0, 0.0, 0.0)


def test_a_pose_in_metres_is_refused_with_a_hint() -> None:
    env = DiningRoomEnv(["dinner fork"], chairs=0)
    env.reset(seed=1)
    with pytest.raises(ValueError, match=r"normalised to \[-1, 1\].*pose_action"):
        env.step({"action": NAVIGATE, "object": 0,
                  "pose": np.array([1.6, 5.0, 1.57], np.float32)})


def test_version_0_is_refused_naming_version_1() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # gymnasium's "out of date"
        with pytest.raises(gymnasium.error.DeprecatedEnv, match="DiningRoom-v1"):
            gymnasium.make("llm_grop/DiningRoom-v0")


def test_close_ends_the_session_and_may_be_repeated() -> None:
    env = DiningRoomEnv(["dinner fork"], chairs=0)
    env.reset(seed=1)
    assert env.session is not None
    env.close()
    env.close()
    assert env.session is None
    with pytest.raises(gymnasium.error.ResetNeeded):
        env.step(FUTILE_PICK)


def _assert_inside(space: gymnasium.spaces.Space[Any], obs: dict[str, Any]) -> None:
    assert isinstance(space, gymnasium.spaces.Dict)
    for key, sub in space.spaces.items():
        assert sub.contains(obs[key]), (key, obs[key], sub)
    assert space.contains(obs)


def _assert_readings_inside(env: gymnasium.Env[Any, Any], tol: float = 0.01) -> None:
    """The simulator's own readings, before the observation clips them, lie within the
    bounds (``tol`` metres or radians): a bound too tight would otherwise hide behind the
    clip."""
    u = env.unwrapped
    robot, objects = u.observation_space["robot"], u.observation_space["objects"]
    r = u.session.robot_pose()
    assert np.all(robot.low[:2] - tol <= (r.x, r.y)) and np.all((r.x, r.y) <= robot.high[:2] + tol)
    states = u.session.objects()
    for k, name in enumerate(u.names):
        xyz = np.array((states[name].x, states[name].y, states[name].z))
        assert np.all(objects.low[k, :3] - tol <= xyz), (name, xyz)
        assert np.all(xyz <= objects.high[k, :3] + tol), (name, xyz)


def _wrapper(env: gymnasium.Env[Any, Any], kind: type) -> gymnasium.Env[Any, Any] | None:
    while isinstance(env, gymnasium.Wrapper):
        if isinstance(env, kind):
            return env
        env = env.env
    return None


def test_a_negative_chair_count_is_one_bad_input() -> None:
    with pytest.raises(ValueError, match=r"^chairs=-1: must be a whole number, 0 or more$"):
        DiningRoomEnv(["mug"], chairs=-1)
