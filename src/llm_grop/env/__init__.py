"""The dining room as a Gymnasium environment, over any simulator with sessions.

Importing this package registers ``llm_grop/DiningRoom-v0``::

    import gymnasium as gym
    import llm_grop.env  # noqa: F401  (registers the environment)

    env = gym.make("llm_grop/DiningRoom-v0", task=8, simulator="mujoco")
"""

from __future__ import annotations

import gymnasium

from llm_grop.env.dining import DiningRoomEnv

__all__ = ["ENV_ID", "DiningRoomEnv"]

#: The registered id.
ENV_ID = "llm_grop/DiningRoom-v0"

if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point="llm_grop.env.dining:DiningRoomEnv")
