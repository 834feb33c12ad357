"""``RigEnv``: the rig as a Gymnasium environment, for designing and tuning a stick-slip
controller offline before it is tested in the loop (msg_docs/gym.md).

An episode is a rig session: the offline loop's ``LoopStepper`` (the ``RigSession`` the node
runs, ticked at the control period, the sensors of the chosen profile), a scenario from the
named set drawn with the reset's seed, the policy's action held over each control period as
the node holds a command. So a policy run here scores as ``drill_sim control`` scores a law,
and ``record=`` writes the episode as a bag ``drill_sim bag resim`` re-runs exactly.

Action: the top drive's command, a motor torque [N·m] within the drive's limits
(``top_drive_mode="torque"``) or the speed command [rad/s] of an ideal speed source
(``"speed"``). Observation (``OBSERVATION``, SI): what the rig's surface sensors show under the
sensor profile, and the speed set-point the scenario asks for. ``info``: the exact state for
evaluation, and at the episode's end ``result``, the run's metrics (``LoopResult.row()``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import ClassVar

import gymnasium as gym
import numpy as np

from ..control import LAWS
from ..control.closed_loop import LoopStepper
from ..control.evaluation import DEFAULT_PERTURBATION, LoopSettings
from ..control.policy import OBSERVATION
from ..control.scenarios import named
from ..core import load_preset
from ..core.distributed import check_string_model
from ..core.parameters import ParameterError, check_number
from ..core.presets import Preset
from ..core.sensor_profile import load_profile
from ..core.sensors import Measured, check_sensor_seed
from ..session.parameter_table import PERTURBATION_RANGE
from ..session.scenario import Scenario
from .payoff import observe_into, reward_of, weight_row

# the observation: one definition for the environment and a policy in the loop
MODES = {"torque": "off", "speed": "kinematic"}        # the loop's law for each action kind
# reward per step: -(speed * ((bit speed - set-point)/set-point)^2 + stick * stuck
#                    + saturation * (action on a limit) + torque_rate * (|dT/dt| / 1 MN m/s)^2)
DEFAULT_WEIGHTS = {"speed": 1.0, "stick": 1.0, "saturation": 0.1, "torque_rate": 0.0}


def action_values(action: object, what: str) -> np.ndarray:
    """``action`` as a flat float array, or ParameterError naming ``what`` if it is not real
    numbers (text, objects, complex or boolean values)."""
    try:
        values = np.asarray(action)
    except (TypeError, ValueError):             # ragged sequences
        values = np.asarray(None)
    if values.dtype.kind not in "iuf":
        raise ParameterError(f"{what} {action!r}: expected real numbers, the top drive's "
                             "commands (motor torque [N m] or speed [rad/s])")
    return values.astype(np.float64).reshape(-1)


class RigEnv(gym.Env):
    """The rig under a policy's top-drive command (module docstring).

    preset: a shipped name or a preset file; string_model: ``lumped`` or ``distributed``
    (default: the preset's); sensor_profile and sensor_seed: as the node's; top_drive_mode:
    ``torque`` or ``speed``; control_period_s: the policy's period h [s], 1e-4 to 0.1 (default
    10 ms; the rig ticks at it, its step the largest divisor of h not above the model's);
    scenarios: a set name
    of ``drill_sim control --scenarios`` (standard, grid, wob_step, speed_ramp, switch_on, a
    rig scenario) or a list of ``Scenario``; reward_weights: ``DEFAULT_WEIGHTS``' names;
    record: a directory each episode is recorded into as a bag (``<record>/episode_<i>``).
    """

    metadata: ClassVar[dict] = {"render_modes": []}

    def __init__(self, preset: str = "base", *, string_model: str | None = None,
                 sensor_profile: str = "ideal", sensor_seed: int = 0,
                 top_drive_mode: str = "torque", control_period_s: float = 0.01,
                 scenarios: str | list[Scenario] = "grid",
                 reward_weights: Mapping[str, float] | None = None,
                 perturbation: float = DEFAULT_PERTURBATION,
                 record: str | Path | None = None) -> None:
        if isinstance(preset, (str, Path)):
            preset = load_preset(preset)
        elif not isinstance(preset, Preset):
            raise ParameterError(f"preset = {preset!r}: expected a shipped preset's name or a "
                                 "preset file's path")
        self.preset = preset
        if top_drive_mode not in MODES:
            raise ParameterError(f"top_drive_mode = {top_drive_mode!r}: expected torque or speed")
        self.top_drive_mode = top_drive_mode
        self.h = check_number("control_period_s", control_period_s, low=1e-4,
                              low_inclusive=True, high=0.1)
        self.scenarios = named(scenarios.split(",")) if isinstance(scenarios, str) \
            else list(scenarios)
        if not self.scenarios or not all(isinstance(x, Scenario) for x in self.scenarios):
            raise ParameterError(f"scenarios = {scenarios!r}: expected a set name or a list of "
                                 "Scenario")
        weights = dict(DEFAULT_WEIGHTS)
        for name, value in (reward_weights or {}).items():
            if name not in DEFAULT_WEIGHTS:
                raise ParameterError(f"reward weight {name!r} is unknown: expected "
                                     f"{', '.join(DEFAULT_WEIGHTS)}")
            weights[name] = check_number(f"reward weight {name}", value, low_inclusive=True)
        self.weights = weights
        self._check_session(string_model, sensor_profile, sensor_seed, perturbation)
        self.settings = LoopSettings(
            law=MODES[top_drive_mode], sample_period_s=self.h,
            string_model=string_model or self.preset.string_model,
            sensor_profile=sensor_profile, sensor_seed=int(sensor_seed),
            perturbation=perturbation)
        self.record = None if record is None else Path(record)
        drive = self.preset.top_drive
        if top_drive_mode == "torque":
            low, high = drive.motor_torque_min_nm, drive.motor_torque_max_nm
        else:
            low, high = 0.0, 40.0
        self.action_space = gym.spaces.Box(np.float64(low), np.float64(high), shape=(1,),
                                           dtype=np.float64)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(len(OBSERVATION),),
                                                dtype=np.float64)
        self.weight_row = weight_row(weights, self.h, float(self.action_space.low[0]),
                                     float(self.action_space.high[0]))
        self.loop: LoopStepper | None = None
        self.episodes = 0
        self.held_action = 0.0          # the command the drive holds now (bumpless take-over)

    @staticmethod
    def _check_session(string_model, sensor_profile, sensor_seed, perturbation) -> None:
        """What the episodes' sessions would refuse, refused here at construction."""
        if string_model is not None:                     # None: the preset's
            check_string_model(string_model)
        load_profile(sensor_profile)                     # a ParameterError naming what is wrong
        check_sensor_seed(sensor_seed, "sensor_seed")
        low, high = PERTURBATION_RANGE
        check_number("perturbation", perturbation, low=low, high=high, low_inclusive=True)

    # ---- the episode -----------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """A scenario drawn with the seed (``options={"scenario": i}`` picks one), the rig on
        its steady start; a scenario's controller switch (``switch_on``) is played by the
        drive's stiff loop, the episode starting at the switch."""
        super().reset(seed=seed)
        self.close()
        i = (int(options["scenario"]) if options and "scenario" in options
             else int(self.np_random.integers(len(self.scenarios))))
        if not 0 <= i < len(self.scenarios):
            raise ParameterError(f"options scenario = {i}: expected 0 to "
                                 f"{len(self.scenarios) - 1} (the set's scenarios)")
        scenario = self.scenarios[i]
        record = None
        if self.record is not None:
            record = self.record / f"episode_{self.episodes}"
        self.episodes += 1
        self.loop = loop = LoopStepper(self.preset, scenario, self.settings, record=record)
        sample, reading = loop.start()
        self.held_action = (loop.rig.commanded_motor_torque_nm if self.top_drive_mode == "torque"
                             else loop.rig.commanded_speed_rad_s)
        if loop.switch_k and self.top_drive_mode == "torque":
            sample, reading = self._stiff_until(loop.switch_k, sample, reading)
        return self._observe(reading), self._info(sample)

    def _stiff_until(self, switch_k: int, sample, reading):
        """The drive's own stiff loop up to the switch (as ``drill_sim control`` plays it)."""
        loop = self.loop
        sup = loop.supervisor("stiff_pi")
        for k in range(switch_k):
            output = sup.step(loop.measure(sample, reading))
            sample, reading = loop.step(output)
            sup.set_speed(float(loop.speed_set[k + 1]))
        self.held_action = float(output)
        return sample, reading

    def step(self, action):
        loop = self.loop
        if loop is None:
            raise RuntimeError("step before reset: call reset() first")
        if loop.k >= loop.n:
            raise RuntimeError(f"step after the episode ended (truncated at sample {loop.n}): "
                               "call reset() first")
        values = action_values(action, "action")
        if values.size != 1:
            raise ParameterError(f"action of {values.size} values: expected one, the "
                                 "top drive's command (shape (1,) or a scalar)")
        value = float(values[0])
        if not math.isfinite(value):
            what = "motor torque [N m]" if self.top_drive_mode == "torque" else "speed [rad/s]"
            raise ParameterError(f"action {value!r}: expected a finite {what}")
        low, high = float(self.action_space.low[0]), float(self.action_space.high[0])
        held = min(max(value, low), high)                 # the drive's limits hold it
        sample, reading = loop.step(held)
        reward = self._reward(sample, value, held)
        self.held_action = held
        truncated = loop.k >= loop.n
        info = self._info(sample)
        if truncated:
            loop.finish(held)
            loop.close()
            info["result"] = loop.result().row()
        return self._observe(reading), reward, False, truncated, info

    def close(self) -> None:
        if self.loop is not None:
            self.loop.close()

    # ---- what the policy sees, what it is paid ---------------------------------------------
    def _observe(self, m: Measured) -> np.ndarray:
        loop = self.loop
        obs = np.empty(len(OBSERVATION))
        observe_into(m.top_drive_speed_rad_s, m.motor_torque_nm, m.surface_torque_nm,
                     m.hook_load_n, float(loop.speed_set[min(loop.k, loop.n)]), obs)
        return obs

    def _info(self, sample) -> dict[str, object]:
        return {"time_s": sample.time_s, "bit_speed_rad_s": sample.bit_speed_rad_s,
                "wob_n": sample.wob_n, "tob_nm": sample.tob_nm, "rop_m_s": sample.rop_m_s,
                "regime": sample.regime, "stuck": sample.stuck,
                "scenario": self.loop.scenario.name}

    def _reward(self, sample, action: float, held: float) -> float:
        loop = self.loop
        return reward_of(sample.bit_speed_rad_s, float(loop.speed_set[min(loop.k, loop.n)]),
                         sample.stuck, action, held, self.held_action,
                         self.top_drive_mode == "torque", self.weight_row)


class ReferencePolicy:
    """A reference law as a policy (observation -> action) for ``RigEnv`` in torque mode: the
    law under the ``Supervisor`` as ``drill_sim control`` runs it, its gains the reference
    tuning for the environment's string and sensors unless given. ``reset(env)`` after each
    ``env.reset``: the law takes over bumplessly from the torque the drive holds."""

    def __init__(self, env: RigEnv, law: str = "z_torque",
                 gains: Mapping[str, float] | None = None) -> None:
        from ..control.evaluation import law_gains, law_top_drive
        from ..control.reference import reference_gains
        from ..control.tuning import pipe_impedance
        torque_laws = [n for n, c in LAWS.items() if c.output_kind == "torque" and n != "off"]
        if law not in torque_laws:
            raise ParameterError(f"law {law!r}: expected a torque law ({', '.join(torque_laws)})")
        if env.top_drive_mode != "torque":
            raise ParameterError("ReferencePolicy drives the motor torque: expected "
                                 "RigEnv(top_drive_mode='torque')")
        drive = law_top_drive(env.preset, law, None)
        s = env.settings
        given = dict(gains) if gains is not None else reference_gains(
            law, env.preset, drive.top_drive_inertia_kg_m2, string_model=s.string_model,
            sensor_profile=s.sensor_profile, sample_period_s=env.h)
        self.law = law
        self.gains = law_gains(LoopSettings(law=law, gains=given), drive)
        self.h, self.z = env.h, pipe_impedance(env.preset)
        self.j = drive.top_drive_inertia_kg_m2
        self.supervisor = None

    def reset(self, env: RigEnv) -> None:
        from ..control.supervisor import Supervisor
        sup = Supervisor(self.h, self.z, self.j, self.law, self.gains,
                         speed_set_rad_s=float(env.loop.speed_set[env.loop.k]))
        sup.last_output = env.held_action
        self.supervisor = sup

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        from ..control.laws import SurfaceMeasurement
        sup = self.supervisor
        if sup is None:
            raise RuntimeError("ReferencePolicy.reset(env) after each env.reset()")
        speed, motor, surface, _hook, setpoint = (float(x) for x in observation)
        sup.set_speed(setpoint)
        return np.array([sup.step(SurfaceMeasurement(0.0, speed, motor, surface))])
