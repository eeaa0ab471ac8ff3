"""The dining room as a Gymnasium environment, over any simulator with sessions.

Importing this package registers ``llm_grop/DiningRoom-v1``::

    import gymnasium as gym
    import llm_grop.env  # noqa: F401  (registers the environment)

    env = gym.make("llm_grop/DiningRoom-v1", task=8, simulator="mujoco",
                   render_mode="rgb_array")
    obs, info = env.reset(seed=0)
    frame = env.render()  # the room from above, height x width x 3 uint8

``gymnasium.make`` wraps it in ``TimeLimit``: an episode is truncated after
:data:`MAX_EPISODE_STEPS` actions (``env.spec.max_episode_steps``; pass
``max_episode_steps=N`` to ``make`` for another limit). Check it with
``gymnasium.utils.env_checker.check_env(env.unwrapped)``.

Version 1 normalises the action's ``pose`` to ``[-1, 1]``
(:meth:`DiningRoomEnv.pose_action` converts metres and radians); ``-v0`` took metres and is
gone, so ``gymnasium.make`` refuses it and names ``-v1``.
"""

from __future__ import annotations

import gymnasium

from llm_grop.env.dining import MAX_EPISODE_STEPS, DiningRoomEnv

__all__ = ["ENV_ID", "MAX_EPISODE_STEPS", "DiningRoomEnv"]

#: The registered id.
ENV_ID = "llm_grop/DiningRoom-v1"

if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point="llm_grop.env.dining:DiningRoomEnv",
                       max_episode_steps=MAX_EPISODE_STEPS)
