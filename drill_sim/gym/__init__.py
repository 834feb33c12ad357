"""drill_sim as a Gymnasium environment (``gymnasium`` from PyPI: ``pip install -e '.[gym]'``).

``import drill_sim.gym`` registers ``drill_sim/Rig-v0``::

    import gymnasium, drill_sim.gym
    env = gymnasium.make("drill_sim/Rig-v0", preset="base", top_drive_mode="torque")
    envs = gymnasium.make_vec("drill_sim/Rig-v0", num_envs=64)   # one compiled call a step

msg_docs/gym.md documents the action, the observation, the reward and the episodes.
"""

from __future__ import annotations

import gymnasium

from .rig_env import DEFAULT_WEIGHTS, OBSERVATION, ReferencePolicy, RigEnv

ENV_ID = "drill_sim/Rig-v0"

if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point="drill_sim.gym.rig_env:RigEnv",
                       vector_entry_point="drill_sim.gym.vector_env:RigVecEnv")

__all__ = ["DEFAULT_WEIGHTS", "ENV_ID", "OBSERVATION", "ReferencePolicy", "RigEnv"]
