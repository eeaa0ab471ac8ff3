"""``DiningRoomEnv``: a mobile manipulator sets a table, one high-level action at a time.

Actions (a ``Dict`` space):

* ``action``: 0 navigate, 1 pick, 2 place;
* ``object``: which object to pick or place (index into the episode's objects);
* ``on``: for place, the object to put it on (an index; the number of objects: the table);
* ``pose``: ``(x, y, theta)`` normalised to ``[-1, 1]``: for navigate, the goal on the
  room's floor (-1 and +1 are its walls, and -pi and pi for ``theta``); for place, the
  object's pose over the target table's top, in the table's frame (-1 and +1 its edges).
  :meth:`DiningRoomEnv.pose_action` converts metres and radians to it. The robot plans
  its own path to a navigation goal.

Observations (a ``Dict`` space, room frame, metres and radians, each bounded by the
room; see :mod:`llm_grop.env.bounds`): ``robot`` ``(x, y, theta)``; ``objects`` one row
``(x, y, z, yaw)`` per object (bottom centre); ``held`` the index of the object in the hand
(the number of objects: none); ``on_table`` which objects rest on the target table;
``chairs`` one row ``(x, y, width, depth, yaw)`` per sensed chair. Frames of the room seen
from above come from ``render()`` with ``render_mode="rgb_array"`` (a render in 3D
simulators, a drawing in 2D ones); ``camera=True``, which also put them in the observation
as ``image``, is deprecated.

Reward: objects that newly rest upright on the target table count +1 each (an object taken
off it, or knocked over, -1), and time costs 1 per 100 simulated seconds. The episode
terminates when every object rests upright on the target table. ``gymnasium.make``
truncates it after :data:`MAX_EPISODE_STEPS` actions (its ``TimeLimit``); an environment
built directly runs until ``max_steps`` actions when that is given, else without limit.
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Sequence
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from llm_grop import seeds
from llm_grop.env.bounds import (
    PoseFrame,
    action_space,
    observation_space,
    room_frame,
    table_frame,
)
from llm_grop.errors import BadInput
from llm_grop.execution import ExecutionPolicy
from llm_grop.execution.judge import judged_place
from llm_grop.files.scene_file import load_scene
from llm_grop.planning.navigation import Navigator
from llm_grop.render.room import room_image
from llm_grop.simulation.base import Session, Simulator
from llm_grop.simulation.registry import DEFAULT_SIMULATOR, create_simulator
from llm_grop.simulation.scenario import prepare_episode
from llm_grop.world.angles import wrap_angle
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.request import items_from_names
from llm_grop.world.scene import Scene
from llm_grop.world.tasks import load_tasks

NAVIGATE, PICK, PLACE = 0, 1, 2
_ACTIONS = ("navigate", "pick", "place")

#: Actions in an episode before ``gymnasium.make``'s ``TimeLimit`` truncates it (the
#: registration's ``max_episode_steps``; ``gymnasium.make(..., max_episode_steps=N)``
#: changes it).
MAX_EPISODE_STEPS = 60


class DiningRoomEnv(gymnasium.Env):
    """The dining room over a simulator (``kinematic2d``, ``mujoco`` or a plugin's with a
    ``session`` method).

    Args:
        objects: catalog names of the objects to set (default: those of ``task``).
        task: a task of the paper's Table I, used when ``objects`` is not given.
        simulator: a simulator name or object.
        scene: a scene, a scene YAML path, or ``None`` for the packaged dining room.
        chairs: chairs sampled near the target table each episode.
        camera: deprecated, to be removed in the next minor release: adds the ``image``
            observation, the frame ``render()`` gives with ``render_mode="rgb_array"``.
        image_size: ``(width, height)`` of ``render()``'s frames, pixels.
        max_steps: actions before the environment truncates the episode itself; ``None``
            (the default): never. ``gymnasium.make`` truncates instead, after
            :data:`MAX_EPISODE_STEPS` (its ``max_episode_steps``).
        render_mode: ``None`` or ``"rgb_array"`` (``render()`` returns the room from
            above, height x width x 3 uint8).
        policy: the tolerances a place is judged by (the executive's): a place whose
            object comes to rest tipped, off its support or away from the pose fails.
    """

    # One frame per action; 4 per second is a watchable pace for a video of an episode.
    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(self, objects: Sequence[str] | None = None, *, task: int = 8,
                 simulator: str | Simulator = DEFAULT_SIMULATOR,
                 scene: Scene | str | None = None, chairs: int = 1, camera: bool = False,
                 image_size: tuple[int, int] = (160, 120), max_steps: int | None = None,
                 render_mode: str | None = None, policy: ExecutionPolicy | None = None
                 ) -> None:
        self.catalog = Catalog.load()
        names = list(objects) if objects is not None else list(load_tasks()[task].objects)
        self.items = items_from_names(names, self.catalog)
        self.names = [i.name for i in self.items]
        self.simulator = create_simulator(simulator) if isinstance(simulator, str) \
            else simulator
        if render_mode not in (None, "rgb_array"):
            raise BadInput("use None or 'rgb_array'", param="render_mode", value=render_mode)
        if max_steps is not None and max_steps < 1:
            raise BadInput("must be at least 1 (or None)", param="max_steps", value=max_steps)
        if not isinstance(chairs, int) or chairs < 0:
            raise BadInput("must be a whole number, 0 or more", param="chairs", value=chairs)
        if camera:
            warnings.warn("DiningRoomEnv(camera=True) is deprecated and will be removed in "
                          "the next minor release: use render_mode='rgb_array' and "
                          "env.render() for the room's image", DeprecationWarning,
                          stacklevel=_caller_stacklevel())
        self.scene = scene if isinstance(scene, Scene) else load_scene(scene)
        self.chairs, self.camera, self.image_size = chairs, camera, image_size
        self.max_steps, self.render_mode = max_steps, render_mode
        self.policy = policy or ExecutionPolicy()
        self.simulator.check(self.scene, self.items)
        self.observation_space = observation_space(self.scene, self.items, chairs,
                                                   image_size if camera else None)
        self.action_space = action_space(len(self.items))
        #: Where a normalised ``pose`` lies, by action: the room's floor for navigate (and
        #: pick, which ignores it), the target table's top for place.
        self.pose_frames: dict[int, PoseFrame] = {
            NAVIGATE: room_frame(self.scene), PICK: room_frame(self.scene),
            PLACE: table_frame(self.scene)}
        self.session: Session | None = None
        self.episode_scene: Scene | None = None
        self._steps = 0
        self._on_table: set[str] = set()

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, Any], dict[str, Any]]:
        """A new episode: chairs and object starts drawn from ``seed``'s streams."""
        super().reset(seed=seed)
        self.close()
        episode_seed = seed if seed is not None else int(self.np_random.integers(2**31))
        scene = prepare_episode(self.scene, self.items, episode_seed, chairs=self.chairs)
        self.episode_scene = scene
        self.session = self.simulator.session(  # type: ignore[attr-defined]
            scene, self.items, seeds.stream(episode_seed, "simulator"),
            replan=Navigator(scene, scene.robot.base_radius_m))
        self._steps = 0
        self._on_table = self._resting()
        return self._observe(), {"seed": episode_seed, "objects": list(self.names)}

    def step(self, action: dict[str, Any]) -> tuple[dict[str, Any], float, bool, bool,
                                                     dict[str, Any]]:
        """Run one high-level action to its end."""
        if self.session is None:
            raise gymnasium.error.ResetNeeded("call reset() before step()")
        action = {"on": len(self.names), **action}
        if not self.action_space.contains(
                {k: np.asarray(v, np.float32) if k == "pose" else v for k, v in action.items()}):
            hint = ""
            if _beyond_unit(action.get("pose")):
                hint = ("; pose is normalised to [-1, 1]: env.unwrapped.pose_action(action, "
                        "x, y, theta) converts metres and radians")
            raise ValueError(f"action {action!r} is not in the action space "
                             f"{self.action_space}{hint}")
        kind = int(action["action"])
        name = self.names[int(action["object"])]
        on = self.names[int(action["on"])] if int(action["on"]) < len(self.names) else None
        x, y, theta = self.pose_frames[kind].to_physical(action["pose"])
        before = self.session.time_s
        if kind == NAVIGATE:
            done = self.session.navigate(Pose2D(x, y, theta))
        elif kind == PICK:
            done = self.session.pick(name)
        else:
            done, _ = judged_place(self.session, self.episode_scene, name, x, y, theta, on,
                                   self.policy)
        self._steps += 1
        now = self._resting()
        gained = len(now - self._on_table) - len(self._on_table - now)
        self._on_table = now
        duration = self.session.time_s - before
        reward = float(gained) - duration / 100.0
        terminated = len(now) == len(self.names)
        truncated = (not terminated and self.max_steps is not None
                     and self._steps >= self.max_steps)
        info = {"action": _ACTIONS[kind], "ok": done.ok, "note": done.note,
                "duration_s": duration, "time_s": self.session.time_s}
        return self._observe(), reward, terminated, truncated, info

    def pose_action(self, action: int, x: float, y: float, theta: float) -> np.ndarray:
        """The normalised ``pose`` for ``action`` at ``(x, y, theta)``, metres and radians:
        a navigation goal in the room frame, a place in the target table's frame.

        Raises :class:`BadInput` for a pose outside the room's floor or the table's top."""
        if action not in self.pose_frames:
            raise BadInput("must be 0 (navigate), 1 (pick) or 2 (place)", param="action",
                           value=action)
        return self.pose_frames[int(action)].to_normalised(x, y, theta)

    def render(self) -> np.ndarray | None:
        """The room from above, height x width x 3 uint8 (``render_mode="rgb_array"``;
        ``None`` otherwise)."""
        if self.render_mode != "rgb_array" or self.session is None:
            return None
        return self._image()

    def close(self) -> None:
        """End the episode's simulator session, if one is open (calling it again is
        harmless)."""
        if self.session is not None:
            self.session.close()
            self.session = None

    def _image(self) -> np.ndarray:
        """The simulator's own view of the room, else a drawing of its state."""
        assert self.session is not None and self.episode_scene is not None
        if self.simulator.supports_pictures:
            return self.simulator.picture("room", self.image_size)
        states = self.session.objects()
        return room_image(self.episode_scene, self.session.robot_pose(),
                          {n: (s.x, s.y) for n, s in states.items()}, self.image_size)

    def _resting(self) -> set[str]:
        assert self.session is not None and self.episode_scene is not None
        target = self.episode_scene.target
        return {n for n, s in self.session.objects().items()
                if s.table == target and not s.held and s.tilt_rad <= self.policy.max_tilt_rad}

    def _observe(self) -> dict[str, Any]:
        assert self.session is not None and self.episode_scene is not None
        space = self.observation_space
        states = self.session.objects()
        r = self.session.robot_pose()
        # Wrapped before the float32 array rounds the yaw, so it is rounded once.
        objects = np.array([(states[n].x, states[n].y, states[n].z, wrap_angle(states[n].yaw))
                            for n in self.names], np.float32)
        chairs = np.zeros((self.chairs, 5), np.float32)
        for k, c in enumerate(self.episode_scene.chairs[:self.chairs]):
            chairs[k] = (c.box.x, c.box.y, c.box.width, c.box.depth, wrap_angle(c.box.yaw))
        held = self.session.held
        obs: dict[str, Any] = {
            "robot": _clip(np.array([r.x, r.y, wrap_angle(r.theta)], np.float32), space["robot"]),
            "objects": _clip(objects, space["objects"]),
            "held": self.names.index(held) if held in self.names else len(self.names),
            "on_table": np.array([n in self._on_table for n in self.names], np.int8),
            "chairs": _clip(chairs, space["chairs"]),
        }
        if self.camera:
            obs["image"] = self._image()
        return obs


def _caller_stacklevel() -> int:
    """The ``stacklevel`` that points a warning at the first caller outside this package
    and Gymnasium (the user's ``gymnasium.make`` or ``DiningRoomEnv`` line)."""
    level, frame = 1, sys._getframe(1)
    while frame.f_back is not None and str(frame.f_globals.get("__name__", "")).startswith(
            ("llm_grop.env", "gymnasium")):
        level, frame = level + 1, frame.f_back
    return level


def _beyond_unit(pose: Any) -> bool:
    """Whether ``pose`` is numbers of which one lies outside ``[-1, 1]`` (metres, say)."""
    try:
        return bool(np.any(np.abs(np.asarray(pose, dtype=float)) > 1.0))
    except (TypeError, ValueError):
        return False


def _clip(x: np.ndarray, box: spaces.Space[Any]) -> np.ndarray:
    """``x`` inside ``box``, float32."""
    assert isinstance(box, spaces.Box)
    # The bounds are physical; a reading a hair past one (an object pressed into the
    # floor by contact, an angle rounded to float32) must still lie in the space.
    return np.clip(x, box.low, box.high).astype(np.float32)
