"""``RigVecEnv``: N rigs as one Gymnasium vector environment, stepped in one compiled call.

``gymnasium.make_vec("drill_sim/Rig-v0", num_envs=N, ...)`` builds it. Each rig is a
``RigEnv`` for what happens once an episode (its scenario drawn with its seed, its session
started, a switch played by the drive's own loop, its result scored), and its state lives in
row i of a ``core.batch.RigBatch``: a step writes the N commands, advances every rig by the
control period in one call of the kernel the session runs, and reads the N samples, the
observations and the rewards with array operations, no Python per rig. So rig i equals a
``RigEnv`` reset with the same seed and given the same actions (``tests/gym/test_vector_env``:
against gymnasium's own ``SyncVectorEnv`` of ``RigEnv``, to 1e-9), with gymnasium's
``NEXT_STEP`` auto-reset: the step after an episode's last resets that rig and ignores its
action.

What the compiled path covers: the lumped and the distributed string, every sensor profile,
either top-drive mode; scenarios without parameter changes, presets without formations, no
recording. Those are refused in one line at construction
(``gymnasium.make_vec(..., vectorization_mode="sync")`` runs them with one ``RigEnv`` per rig).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv

from ..control.closed_loop import SERIES
from ..core import state_layout as sl
from ..core.batch import RigBatch
from ..core.parameters import ParameterError
from ..core.rig_step import NR, scale_row
from ..session.scenario import Scenario
from .rig_env import RigEnv, action_values
from .vector_step import (
    F_BIT,
    F_OUTPUT,
    F_STUCK,
    F_TIME,
    F_WOB,
    NF,
    step_rigs,
)

MAX_RIGS = 65_536


class RigVecEnv(VectorEnv):
    """``num_envs`` rigs of one preset, each with its own scenario draw and seed (module
    docstring); the other arguments are ``RigEnv``'s."""

    metadata: ClassVar[dict] = {"render_modes": [], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, num_envs: int = 1, preset: str = "base", *,
                 string_model: str | None = None, sensor_profile: str = "ideal",
                 sensor_seed: int = 0, top_drive_mode: str = "torque",
                 control_period_s: float = 0.01, scenarios: str | list[Scenario] = "grid",
                 reward_weights: Mapping[str, float] | None = None,
                 perturbation: float | None = None,
                 record: str | Path | None = None) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) \
                or not 1 <= num_envs <= MAX_RIGS:
            raise ParameterError(f"num_envs = {num_envs!r}: expected a whole number of rigs "
                                 f"from 1 to {MAX_RIGS}")
        kwargs: dict[str, Any] = dict(
            string_model=string_model, sensor_profile=sensor_profile, sensor_seed=sensor_seed,
            top_drive_mode=top_drive_mode, control_period_s=control_period_s,
            scenarios=scenarios, reward_weights=reward_weights)
        if perturbation is not None:
            kwargs["perturbation"] = perturbation
        self.envs = [RigEnv(preset, **kwargs) for _ in range(int(num_envs))]
        first = self.envs[0]
        self._refuse_what_is_not_compiled(first, record)
        self.num_envs = int(num_envs)
        self.single_action_space = first.action_space
        self.single_observation_space = first.observation_space
        self.action_space = gym.vector.utils.batch_space(first.action_space, self.num_envs)
        self.observation_space = gym.vector.utils.batch_space(first.observation_space,
                                                              self.num_envs)
        self.torque = top_drive_mode == "torque"
        self._low = float(first.action_space.low[0])
        self._high = float(first.action_space.high[0])
        self._batch: RigBatch | None = None
        self._args: tuple | None = None
        n = self.num_envs
        self._k = np.zeros(n, dtype=np.int64)             # each rig's sample index
        self._n = np.zeros(n, dtype=np.int64)             # each episode's last sample
        self._window_k = np.zeros(n, dtype=np.int64)
        self._held = np.zeros(n)                          # the command each drive holds
        self._speed_cmd = np.zeros(n)                     # the rig's held speed command [rad/s]
        self._autoreset = np.zeros(n, dtype=bool)
        self._speed_set = np.zeros((n, 1))                # per rig, per sample [rad/s]
        self._hook = np.zeros((n, 1))                     # per rig, per sample [N]
        self._series = np.zeros((NF, n, 1))               # SERIES, per rig, per sample
        self._last = np.zeros((NF, n))                    # SERIES of each rig's last sample
        self._tob = np.zeros(n)                           # each rig's last TOB [N m]
        self._window_now = np.zeros(n, dtype=bool)
        self._refill = np.zeros(n, dtype=bool)              # a rig's sensors want new noise
        # the ideal profile reads the sample itself (tests/gym: against RigEnv, which measures)
        self._exact = first.settings.sensor_profile == "ideal"
        self._obs = np.zeros((n, *first.observation_space.shape))
        self._reward = np.zeros(n)
        self._names = np.full(n, "", dtype=object)

    @staticmethod
    def _refuse_what_is_not_compiled(env: RigEnv, record) -> None:
        why = None
        if record is not None:
            why = "record (episodes are recorded by RigEnv)"
        elif any(x.changes for x in env.scenarios):
            names = ", ".join(x.name for x in env.scenarios if x.changes)
            why = f"scenarios that change parameters ({names})"
        elif env.preset.string is not None and env.preset.string.well is not None \
                and env.preset.string.well.formations:
            why = "a preset with formations along the hole"
        if why is not None:
            raise ParameterError(f"the vector environment does not run {why}; use "
                                 "gymnasium.make_vec(..., vectorization_mode='sync')")

    # ---- episodes ---------------------------------------------------------------------------
    def reset(self, *, seed: int | list[int] | None = None, options: dict | None = None):
        """Every rig reset (``RigEnv.reset``; rig i with ``seed + i``, or ``seed[i]``)."""
        n = self.num_envs
        seeds = (list(seed) if isinstance(seed, (list, tuple, np.ndarray)) else
                 [None] * n if seed is None else [int(seed) + i for i in range(n)])
        if len(seeds) != n:
            raise ParameterError(f"{len(seeds)} seeds for {n} rigs: expected one each")
        obs = np.zeros((n, *self.single_observation_space.shape))
        infos: dict[str, Any] = {}
        for i in range(n):
            obs[i], info = self.envs[i].reset(seed=seeds[i], options=options)
            self._adopt(i)
            infos = self._add_info(infos, info, i)
        self._autoreset[:] = False
        return obs, infos

    def _adopt(self, i: int) -> None:
        """Rig i's new episode into the batch: its state, commands, schedule and series."""
        env = self.envs[i]
        loop = env.loop
        rig = loop.rig
        bank = loop.session.sensors
        if self._batch is None:
            self._batch = RigBatch(self.num_envs, rig.sim, bank)
            self._scales = rig.scales
            self._steps_per_tick = loop.session.steps_per_tick
            self._max_speed = float(loop.session.p["max_top_drive_speed_rad_s"])
            self._scale_row = scale_row(rig.params, rig.dt_s)
            self._weight_row = env.weight_row
            self._sample_row = np.zeros(NR)
        elif rig.scales != self._scales or loop.session.steps_per_tick != \
                self._steps_per_tick:
            raise ParameterError("the vector environment's rigs must share their scales and "
                                 "step (one preset)")
        self._batch.adopt(i, rig.sim, bank)
        n_i = loop.n
        if self._speed_set.shape[1] < n_i + 1:
            self._grow(n_i + 1)
        self._speed_set[i, :n_i + 1] = loop.speed_set
        self._hook[i, :n_i + 1] = loop.hook
        self._k[i], self._n[i], self._window_k[i] = loop.k, n_i, loop.window_k
        self._held[i] = env.held_action
        self._speed_cmd[i] = rig.commanded_speed_rad_s
        sample = loop.session.last[1]
        for f, name in enumerate(SERIES):
            self._series[f, i, :loop.k] = loop.series[name][:loop.k]
            if f != F_OUTPUT:
                self._last[f, i] = getattr(sample, name)
        self._names[i] = loop.scenario.name

    def _grow(self, size: int) -> None:
        """Room for episodes of ``size`` samples."""
        n = self.num_envs
        speed_set, hook = np.zeros((n, size)), np.zeros((n, size))
        series = np.zeros((NF, n, size))
        old = self._speed_set.shape[1]
        speed_set[:, :old], hook[:, :old] = self._speed_set, self._hook
        series[:, :, :old] = self._series
        self._speed_set, self._hook, self._series = speed_set, hook, series
        self._args = None                 # step_rigs' arguments hold the old series

    # ---- a step of every rig --------------------------------------------------------------------
    def step(self, actions):
        n = self.num_envs
        values = action_values(actions, "actions").reshape(np.shape(actions))
        if values.size != n or values.ndim > 2:
            raise ParameterError(f"actions of shape {values.shape}: expected ({n}, 1), each "
                                 "rig's top-drive command")
        values = values.reshape(n, -1)
        if values.shape[1] != 1:
            raise ParameterError(f"actions of shape {np.shape(actions)}: expected ({n}, 1), "
                                 "each rig's top-drive command")
        values = np.ascontiguousarray(values[:, 0])
        live = ~self._autoreset
        finite = np.isfinite(values)
        if not finite.all() and (live & ~finite).any():
            i = int(np.flatnonzero(live & ~finite)[0])
            what = "motor torque [N m]" if self.torque else "speed [rad/s]"
            raise ParameterError(f"action of rig {i} = {values[i]!r}: expected a finite {what}")
        if not self.torque:
            fast = live & (np.minimum(values, self._high) > self._max_speed)
            if fast.any():
                i = int(np.flatnonzero(fast)[0])
                raise ParameterError(f"the loop's ~/cmd/top_drive command was refused: rig {i}'s "
                                     f"speed {min(values[i], self._high)!r} rad/s is above "
                                     f"max_top_drive_speed_rad_s {self._max_speed:g}")
        b, obs, reward = self._batch, self._obs, self._reward
        if self._args is None:
            self._args = self._fixed_args()
        rigs, string, record, constants, sensors, outputs = self._args
        refused = step_rigs(
            rigs, string, (live, self.torque, self._steps_per_tick, values, self._held,
                           self._speed_set, self._hook, self._k, self._n, self._window_k,
                           self._speed_cmd),
            record, constants, sensors, outputs)
        if refused >= 0:              # the rigs before it have stepped: the batch is spent
            try:
                self.envs[refused].loop.rig.sim._refuse_step()
            except ParameterError as exc:
                raise ParameterError(f"rig {refused}: {exc}; reset the environment") from None
        # the rare per-rig events (flatnonzero costs ~3 us: looked for only when one came)
        for i in np.flatnonzero(self._refill) if self._refill.any() else ():
            self.envs[i].loop.session.sensors._refill()
        for i in np.flatnonzero(self._window_now) if self._window_now.any() else ():
            self.envs[i].loop.rig.reset_metrics_window()
        obs, reward = obs.copy(), reward.copy()
        truncated = live & (self._k >= self._n)
        last = self._last
        infos = {"time_s": last[F_TIME].copy(), "bit_speed_rad_s": last[F_BIT].copy(),
                 "wob_n": last[F_WOB].copy(), "tob_nm": self._tob.copy(),
                 "rop_m_s": b.x[:, sl.X_V] * self._scales.velocity_m_s,
                 "regime": b.k[:, sl.K_REGIME].copy(), "stuck": last[F_STUCK] != 0.0,
                 "scenario": self._names.copy()}
        mask = live.copy()                  # every key's: the live rigs have them all
        infos |= {"_" + key: mask for key in list(infos)}
        for i in np.flatnonzero(truncated) if truncated.any() else ():
            infos = self._add_info(infos, {"result": self._finish(i)}, i)
        # NEXT_STEP: the rigs that ended last step start their next episode now
        for i in np.flatnonzero(self._autoreset) if self._autoreset.any() else ():
            obs[i], info = self.envs[i].reset()
            self._adopt(i)
            reward[i] = 0.0
            infos = self._add_info(infos, info, i)
        self._autoreset = truncated
        return obs, reward, np.zeros(n, dtype=bool), truncated.copy(), infos

    def _fixed_args(self) -> tuple:
        """``step_rigs``' arguments that stay from step to step (the batch's arrays, the
        series, the sensors', the outputs), made once: a step builds only its schedule."""
        b = self._batch
        s = b.bank
        return ((b.x, b.k, b.surf, b.p, b.c, b.acc), (b.distributed, *b.string_args),
                (self._last, self._series, self._tob), (self._scale_row, self._weight_row),
                (s["_par"], s["_state"], s["_istate"], s["_ring"], s["_noise"], s["_window"],
                 b.window_s, s["_x"], s["_out"], s["_fresh"], self._refill, self._exact),
                (self._obs, self._reward, self._window_now, b.no_rows, self._sample_row))

    def _finish(self, i: int) -> dict[str, object]:
        """Rig i's episode ended: its series back in its loop, scored as RigEnv scores it
        (``info["result"]``)."""
        loop = self.envs[i].loop
        n_i = int(self._n[i])
        self._series[:, i, n_i] = self._last[:, i]
        self._series[F_OUTPUT, i, n_i] = self._held[i]
        for f, name in enumerate(SERIES):
            loop.series[name][:] = self._series[f, i, :n_i + 1]
        loop.k = n_i
        loop.close()
        return loop.result().row()

    def close_extras(self, **kwargs) -> None:
        for env in self.envs:
            env.close()
