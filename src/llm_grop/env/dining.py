"""``DiningRoomEnv``: a mobile manipulator sets a table, one high-level action at a time.

Actions (a ``Dict`` space):

* ``action``: 0 navigate, 1 pick, 2 place;
* ``object``: which object to pick or place (index into the episode's objects);
* ``on``: for place, the object to put it on (an index; the number of objects: the table);
* ``pose``: ``(x, y, theta)``: for navigate, the goal in the room frame; for place, the
  object's pose in the target table's frame (metres, radians). The robot plans its own
  path to a navigation goal.

Observations (a ``Dict`` space, room frame, metres and radians): ``robot`` ``(x, y,
theta)``; ``objects`` one row ``(x, y, z, yaw)`` per object (bottom centre); ``held`` the
index of the object in the hand (the number of objects: none); ``on_table`` which objects
rest on the target table; ``chairs`` one row ``(x, y, width, depth, yaw)`` per sensed
chair; and with ``camera=True`` ``image``, the room seen from above (a render in 3D
simulators, a drawing in 2D ones).

Reward: objects that newly rest upright on the target table count +1 each (an object taken
off it, or knocked over, -1), and time costs 1 per 100 simulated seconds. The episode
terminates when every object rests upright on the target table and is truncated after
``max_steps`` actions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from llm_grop import seeds
from llm_grop.errors import BadInput
from llm_grop.execution import ExecutionPolicy
from llm_grop.execution.judge import judged_place
from llm_grop.planning.navigation import Navigator
from llm_grop.render.room import room_image
from llm_grop.simulation.base import Session, Simulator
from llm_grop.simulation.registry import create_simulator
from llm_grop.simulation.scenario import prepare_episode
from llm_grop.world.catalog import Catalog
from llm_grop.world.geometry2d import Pose2D
from llm_grop.world.request import items_from_names
from llm_grop.world.scene import Scene
from llm_grop.world.scene_file import load_scene
from llm_grop.world.tasks import load_tasks

NAVIGATE, PICK, PLACE = 0, 1, 2
_ACTIONS = ("navigate", "pick", "place")


class DiningRoomEnv(gymnasium.Env):
    """The dining room over a simulator (``kinematic2d``, ``mujoco`` or a plugin's with a
    ``session`` method).

    Args:
        objects: catalog names of the objects to set (default: those of ``task``).
        task: a task of the paper's Table I, used when ``objects`` is not given.
        simulator: a simulator name or object.
        scene: a scene, a scene YAML path, or ``None`` for the packaged dining room.
        chairs: chairs sampled near the target table each episode.
        camera: add the ``image`` observation.
        image_size: ``(width, height)`` of the image and of ``render()``, pixels.
        max_steps: actions before the episode is truncated.
        render_mode: ``None`` or ``"rgb_array"``.
        policy: the tolerances a place is judged by (the executive's): a place whose
            object comes to rest tipped, off its support or away from the pose fails.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(self, objects: Sequence[str] | None = None, *, task: int = 8,
                 simulator: str | Simulator = "kinematic2d",
                 scene: Scene | str | None = None, chairs: int = 1, camera: bool = False,
                 image_size: tuple[int, int] = (160, 120), max_steps: int = 60,
                 render_mode: str | None = None, policy: ExecutionPolicy | None = None
                 ) -> None:
        self.catalog = Catalog.load()
        names = list(objects) if objects is not None else list(load_tasks()[task].objects)
        self.items = items_from_names(names, self.catalog)
        self.names = [i.name for i in self.items]
        self.simulator = create_simulator(simulator) if isinstance(simulator, str) \
            else simulator
        if not hasattr(self.simulator, "session"):
            raise BadInput(f"simulator {self.simulator.name!r} cannot be driven one action "
                           "at a time (it has no session)")
        if render_mode not in (None, "rgb_array"):
            raise BadInput(f"render_mode: {render_mode!r}; use None or 'rgb_array'")
        self.scene = scene if isinstance(scene, Scene) else load_scene(scene)
        self.chairs, self.camera, self.image_size = chairs, camera, image_size
        self.max_steps, self.render_mode = max_steps, render_mode
        self.policy = policy or ExecutionPolicy()
        if hasattr(self.simulator, "check"):
            self.simulator.check(self.scene, self.items)
        n, w, d = len(self.items), self.scene.width, self.scene.depth
        obs: dict[str, spaces.Space[Any]] = {
            "robot": spaces.Box(np.array([0, 0, -math.pi], np.float32),
                                np.array([w, d, math.pi], np.float32), dtype=np.float32),
            "objects": spaces.Box(np.tile(np.array([0, 0, 0, -math.pi], np.float32), (n, 1)),
                                  np.tile(np.array([w, d, 3, math.pi], np.float32), (n, 1)),
                                  dtype=np.float32),
            "held": spaces.Discrete(n + 1),
            "on_table": spaces.MultiBinary(n),
            "chairs": spaces.Box(-10.0, 10.0 + max(w, d), (chairs, 5), dtype=np.float32),
        }
        if camera:
            obs["image"] = spaces.Box(0, 255, (image_size[1], image_size[0], 3), np.uint8)
        self.observation_space = spaces.Dict(obs)
        self.action_space = spaces.Dict({
            "action": spaces.Discrete(3),
            "object": spaces.Discrete(n),
            "on": spaces.Discrete(n + 1),
            "pose": spaces.Box(np.array([-w, -d, -math.pi], np.float32),
                               np.array([w, d, math.pi], np.float32), dtype=np.float32),
        })
        self.session: Session | None = None
        self.episode_scene: Scene | None = None
        self._steps = 0
        self._on_table: set[str] = set()

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, Any], dict[str, Any]]:
        """A new episode: chairs and object starts drawn from ``seed``'s streams."""
        super().reset(seed=seed)
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
            raise ValueError(f"action {action!r} is not in the action space "
                             f"{self.action_space}")
        kind = int(action["action"])
        name = self.names[int(action["object"])]
        on = self.names[int(action["on"])] if int(action["on"]) < len(self.names) else None
        x, y, theta = (float(v) for v in np.asarray(action["pose"], dtype=float))
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
        truncated = not terminated and self._steps >= self.max_steps
        info = {"action": _ACTIONS[kind], "ok": done.ok, "note": done.note,
                "duration_s": duration, "time_s": self.session.time_s}
        return self._observe(), reward, terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """The room from above (``render_mode="rgb_array"``)."""
        if self.render_mode != "rgb_array" or self.session is None:
            return None
        return self._image()

    def _image(self) -> np.ndarray:
        """The simulator's own view of the room, else a drawing of its state."""
        assert self.session is not None and self.episode_scene is not None
        if hasattr(self.session, "picture"):
            return self.session.picture("room", self.image_size)  # type: ignore[no-any-return]
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
        objects = np.array([(states[n].x, states[n].y, states[n].z, states[n].yaw)
                            for n in self.names], np.float32)
        objects[:, 3] = [_wrap(a) for a in objects[:, 3]]
        chairs = np.zeros((self.chairs, 5), np.float32)
        for k, c in enumerate(self.episode_scene.chairs[:self.chairs]):
            chairs[k] = (c.box.x, c.box.y, c.box.width, c.box.depth, _wrap(c.box.yaw))
        held = self.session.held
        obs: dict[str, Any] = {
            "robot": _clip(np.array([r.x, r.y, _wrap(r.theta)], np.float32), space["robot"]),
            "objects": _clip(objects, space["objects"]),
            "held": self.names.index(held) if held in self.names else len(self.names),
            "on_table": np.array([n in self._on_table for n in self.names], np.int8),
            "chairs": _clip(chairs, space["chairs"]),
        }
        if self.camera:
            obs["image"] = self._image()
        return obs


def _wrap(a: float) -> float:
    return float((a + math.pi) % (2 * math.pi) - math.pi)


def _clip(x: np.ndarray, box: spaces.Space[Any]) -> np.ndarray:
    assert isinstance(box, spaces.Box)
    return np.clip(x, box.low, box.high).astype(np.float32)
