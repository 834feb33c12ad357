"""Any Python policy with the Gymnasium environment's interface as a law of the motor torque,
so that the object designed or trained offline (``drill_sim.gym``) is the one tested against
the rig node (``drill_sim_controller -p law:=policy -p policy:=package.module:callable``).

A policy is a callable ``policy(observation) -> action``: the observation a flat array of
``OBSERVATION`` (SI, what the rig's surface sensors show and the speed set-point), the action
the motor torque [N·m] (a scalar or an array of one). The drive's limits hold the torque.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable

import numpy as np

from ..core.parameters import ParameterError
from .laws import Law, SurfaceMeasurement

POLICY_LAW = "policy"
OBSERVATION = ("top_drive_speed_rad_s", "motor_torque_nm", "surface_torque_nm", "hook_load_n",
               "speed_setpoint_rad_s")
Policy = Callable[[np.ndarray], object]


def load_policy(spec: str) -> Policy:
    """The callable ``package.module:name`` names (ParameterError saying what is wrong)."""
    module_name, sep, attr = str(spec).partition(":")
    if not sep or not module_name or not attr:
        raise ParameterError(f"policy = {spec!r}: expected package.module:callable, e.g. "
                             "drill_sim.control.policy:proportional_speed_policy")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise ParameterError(f"policy = {spec!r}: cannot import {module_name} ({exc})") \
            from None
    policy = module
    for part in attr.split("."):
        policy = getattr(policy, part, None)
        if policy is None:
            raise ParameterError(f"policy = {spec!r}: {module_name} has no {attr}")
    if not callable(policy):
        raise ParameterError(f"policy = {spec!r}: {attr} is not callable")
    return policy


def proportional_speed_policy(observation: np.ndarray) -> np.ndarray:
    """An example: the surface torque fed forward plus 20 kN·m·s/rad times the speed error,
    a stiff speed loop without memory (for trying the interface, not for curing stick-slip)."""
    speed, _motor, surface, _hook, setpoint = observation
    return np.array([surface + 2.0e4 * (setpoint - speed)])


class PolicyLaw(Law):
    """A policy as a law: each step builds the observation from the sample (and the hook load
    the caller sets) and returns the policy's action. An action that is not one finite
    number, or a policy that raises, holds the last output and is counted in ``refused``
    (``last_problem`` says why)."""

    __slots__ = ("_obs", "hook_load_n", "last_output", "last_problem", "policy", "refused")
    name = POLICY_LAW
    GAINS = ()

    def __init__(self, h_s: float, impedance_nm_s_rad: float, top_drive_inertia_kg_m2: float,
                 policy: Policy) -> None:
        super().__init__(h_s, impedance_nm_s_rad, top_drive_inertia_kg_m2)
        if not callable(policy):
            raise ParameterError(f"policy {policy!r} is not callable")
        self.policy = policy
        self.hook_load_n = math.nan         # set by the caller before each step
        self.last_output: float | None = None
        self.refused = 0
        self.last_problem = ""
        self._obs = np.zeros(len(OBSERVATION))

    def step(self, m: SurfaceMeasurement) -> float:
        obs = self._obs
        obs[:] = (m.top_drive_speed_rad_s, m.motor_torque_nm, m.surface_torque_nm,
                  self.hook_load_n, self.speed_set_rad_s)
        try:
            values = np.asarray(self.policy(obs.copy()), dtype=np.float64).reshape(-1)
            if values.size != 1 or not math.isfinite(values[0]):
                raise ValueError(f"action {values.tolist()}: expected one finite motor "
                                 "torque [N m]")
            out = float(values[0])
        except Exception as exc:      # a user's code: any failure holds, and is said
            self.refused += 1
            self.last_problem = f"{type(exc).__name__}: {exc}"
            return self.last_output if self.last_output is not None else m.motor_torque_nm
        self.last_output = out
        return out

    def bumpless_start(self, current_output: float, measurement: SurfaceMeasurement) -> float:
        """A policy has no state to align: its first action, from the first sample."""
        self.last_output = current_output
        return self.step(measurement)
