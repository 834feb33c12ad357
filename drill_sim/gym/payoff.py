"""What a policy sees and what it is paid at each step, compiled once: ``RigEnv`` and the
vector environment's step (``vector_step``) both call these, so a row of the vector
environment equals a ``RigEnv`` to the bit.

The reward per step is -(speed ((bit speed - set-point)/set-point)^2 + stick (bit stuck)
+ saturation (action on a limit) + torque_rate (|dT/dt| / 1 MN m/s)^2), its weights in the row
``weights`` (``WEIGHT_FIELDS``: the four weights, the control period h [s], the action's low
and high limits).
"""

from __future__ import annotations

import numpy as np
from numba import njit

WEIGHT_FIELDS = ("speed", "stick", "saturation", "torque_rate", "control_period_s",
                 "action_low", "action_high")
W_SPEED, W_STICK, W_SATURATION, W_RATE, W_H, W_LOW, W_HIGH = range(7)


def weight_row(weights: dict[str, float], control_period_s: float, low: float,
               high: float) -> np.ndarray:
    """The row ``WEIGHT_FIELDS`` of a reward's named weights, the period [s] and the action's
    limits."""
    return np.array([weights["speed"], weights["stick"], weights["saturation"],
                     weights["torque_rate"], control_period_s, low, high], dtype=np.float64)


@njit(cache=True, inline="always")
def observe_into(top_drive_speed_rad_s, motor_torque_nm, surface_torque_nm, hook_load_n,
                 speed_setpoint_rad_s, obs):
    """The observation (``control.policy.OBSERVATION``'s order, SI) into ``obs``."""
    obs[0] = top_drive_speed_rad_s
    obs[1] = motor_torque_nm
    obs[2] = surface_torque_nm
    obs[3] = hook_load_n
    obs[4] = speed_setpoint_rad_s


@njit(cache=True, inline="always")
def reward_of(bit_speed_rad_s, speed_setpoint_rad_s, stuck, action, held_action, before,
              torque_mode, weights):
    """The step's reward (module docstring): ``action`` as the policy gave it, ``held_action``
    as the drive's limits held it, ``before`` the one held the step before (the torque rate
    counts in torque mode only)."""
    dev = ((bit_speed_rad_s - speed_setpoint_rad_s) / max(speed_setpoint_rad_s, 1e-3)) ** 2
    rate = 0.0
    if torque_mode:
        rate = (abs(held_action - before) / weights[W_H] / 1e6) ** 2
    on_limit = action != held_action or held_action == weights[W_LOW] \
        or held_action == weights[W_HIGH]
    return -(weights[W_SPEED] * dev + weights[W_STICK] * (1.0 if stuck else 0.0)
             + weights[W_SATURATION] * (1.0 if on_limit else 0.0) + weights[W_RATE] * rate)
