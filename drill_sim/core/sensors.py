"""The rig's sensors: what a controller on a real rig would read instead of the exact state.

``SensorBank(profile, dt_s, seed)`` turns the model's exact values into measured ones, one
channel per quantity of ``sensor_profile.CHANNELS``. Each call of ``measure(time_s, sample)``
is one tick; per channel, in the order a physical chain has them:

1. first-order low-pass of time constant ``filter_tau_s`` (the sensor's or the anti-alias
   filter), exact for an input held between calls: y += (1 - exp(-dt/tau)) (x_prev - y);
2. sampling at ``rate_hz`` (instants t0 + k/rate, each taken at the first call at or after it;
   every call without a rate), adding ``bias`` and ``noise_std`` * N(0, 1), then rounding to a
   multiple of ``quantum``;
3. a delay: the sample taken at instant t_k is shown from the first call at or after
   t_k + ``delay_s`` (a delay of D sample periods is exactly D samples);
4. a zero-order hold: the value shown stays until the next one; ``fresh`` says which channels
   showed a new value at this call. Before its first value arrives a channel shows the first
   sample without noise (as if the signal had been steady before the start).

The stick-slip severity is computed downhole: (max - min) / (2 mean) of the exact bit speed over
consecutive windows of ``window_s`` (the mean over the window's calls), held between window
ends (0 before the first; capped at ``SEVERITY_MAX``, which a bit stopped for a whole window
shows), then measured like the others.

Noise comes from one numpy Generator per channel, spawned from ``SeedSequence(seed)`` (so a
channel's noise does not depend on the other channels' rates) and drawn in blocks into a fixed
buffer; the delay lives in a fixed ring buffer. The kernel allocates nothing (a call builds only
its inputs and result), and the whole bank is one compiled kernel call; the same profile, dt_s,
seed and calls give the same measurements bit for bit.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from . import stick_slip
from .numba_cache import follow
from .parameters import ParameterError
from .sensor_profile import (
    CHANNELS,
    MAX_BUFFERED_SAMPLES,
    SEVERITY,
    SensorProfile,
    load_profile,
)
from .stick_slip import severity_index

follow(__file__, stick_slip.__file__)       # the cache follows the SSI it compiles
_severity_index = nb.njit(cache=True)(severity_index)
SEVERITY_MAX = 10.0          # the severity shown when the bit's mean speed over a window is <= 0
NOISE_BLOCK = 4096           # normal deviates drawn at a time, per channel
_SAMPLE_FIELDS = CHANNELS[:-1]
# the channels' indices, for compiled callers (the vector environment's step)
M_SURFACE, M_TD_SPEED, M_MOTOR, M_HOOK, M_WOB, M_TOB, M_BIT = (
    CHANNELS.index(name) for name in ("surface_torque_nm", "top_drive_speed_rad_s",
                                      "motor_torque_nm", "hook_load_n", "wob_n", "tob_nm",
                                      "bit_speed_rad_s"))
_BIT_SPEED = CHANNELS.index("bit_speed_rad_s")
_SEV = CHANNELS.index(SEVERITY)

# kernel array columns
P_PERIOD, P_DELAY, P_STD, P_BIAS, P_QUANTUM, P_TAU = range(6)
S_Y, S_PREV_X, S_LAST_T, S_T0, S_HELD = range(5)
I_INIT, I_NEXT_K, I_HEAD, I_COUNT, I_NOISE = range(5)
W_END, W_MIN, W_MAX, W_SUM, W_N, W_VALUE, W_LEN = range(7)

MAX_SENSOR_SEED = 2**31 - 1     # a non-negative 32-bit seed: every tool takes the same range


class Measured(NamedTuple):
    """What the rig's sensors show at one call, SI; ``fresh[i]`` is True when channel
    ``CHANNELS[i]`` showed a new value at this call (else its last value is held)."""

    time_s: float
    surface_torque_nm: float
    top_drive_speed_rad_s: float
    motor_torque_nm: float
    hook_load_n: float
    wob_n: float
    tob_nm: float
    bit_speed_rad_s: float
    stick_slip_severity: float
    fresh: tuple[bool, ...]


def exact_measured(sample: object, severity: float = 0.0) -> Measured:
    """The exact values of ``sample`` (a ``RigSample``) as a reading, all fresh; ``severity``
    for the one channel a sample does not hold."""
    return Measured(sample.time_s, *(getattr(sample, c) for c in _SAMPLE_FIELDS), severity,
                    (True,) * len(CHANNELS))


def session_sensors(p: dict[str, object], dt_s: float,
                    profile: SensorProfile | None = None) -> SensorBank:
    """The sensors of a node session's parameters ``sensor_profile`` and ``sensor_seed``
    (ideal and 0 when absent, as in sessions recorded before they existed), called at most
    once per model step ``dt_s`` [s]; ``profile`` overrides the named one (a recorded copy)."""
    if profile is None:
        profile = load_profile(str(p.get("sensor_profile", "ideal")))
    return SensorBank(profile, dt_s, int(p.get("sensor_seed", 0)))


def check_sensor_seed(seed: object, name: str = "sensor seed") -> None:
    """A seed every tool takes: a whole number from 0 to MAX_SENSOR_SEED, or ParameterError
    naming ``name``."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) \
            or not 0 <= seed <= MAX_SENSOR_SEED:
        raise ParameterError(f"{name} = {seed!r}: expected a whole number from 0 to "
                             f"{MAX_SENSOR_SEED}")


class SensorBank:
    """The sensors of one profile, called once per tick of ``dt_s`` [s] (the shortest interval
    between calls the delay buffers are sized for), with noise seeded by ``seed``."""

    def __init__(self, profile: SensorProfile | str, dt_s: float, seed: int = 0) -> None:
        self.profile = load_profile(profile) if isinstance(profile, str) else profile
        if not (isinstance(dt_s, (int, float)) and math.isfinite(dt_s) and dt_s > 0):
            raise ParameterError(f"dt_s = {dt_s!r}: expected a positive number of seconds")
        check_sensor_seed(seed)
        self.dt_s, self.seed = float(dt_s), int(seed)
        n = len(CHANNELS)
        specs = [self.profile.channels[c] for c in CHANNELS]
        self._par = np.array([[s.period_s, s.delay_s, s.noise_std, s.bias, s.quantum,
                               s.filter_tau_s] for s in specs], dtype=np.float64)
        # samples waiting out the delay: at most delay / (sampling interval) + 2
        waiting = [s.delay_s / max(s.period_s, self.dt_s) for s in specs]
        for c, w in zip(CHANNELS, waiting, strict=True):
            if w > MAX_BUFFERED_SAMPLES:
                raise ParameterError(
                    f"sensor profile {self.profile.name!r}, channel {c}: delay_s = "
                    f"{self.profile.channels[c].delay_s:g} s sampled every "
                    f"{max(self.profile.channels[c].period_s, self.dt_s):g} s would buffer more "
                    f"than {MAX_BUFFERED_SAMPLES:,} samples; expected a shorter delay or a "
                    "lower rate_hz")
        cap = max(math.ceil(w) for w in waiting) + 2
        self._ring = np.zeros((n, cap, 2))
        self._noise = np.zeros((n, NOISE_BLOCK))
        self._state = np.zeros((n, 5))
        self._istate = np.zeros((n, 5), dtype=np.int64)
        self._window = np.zeros(W_LEN)
        self._x = np.zeros(n)
        self._out = np.zeros(n)
        self._fresh = np.zeros(n, dtype=np.bool_)
        self._window_s = self.profile.severity_window_s
        self.reset()

    def reset(self) -> None:
        """Back to the state before the first call: filters, delays and the severity window
        empty, every channel's noise stream at its start."""
        self._rngs = [np.random.Generator(np.random.PCG64(s))
                      for s in np.random.SeedSequence(self.seed).spawn(len(CHANNELS))]
        for rng, row in zip(self._rngs, self._noise, strict=True):
            rng.standard_normal(out=row)
        self._state[:] = 0.0
        self._last_time_s = -math.inf
        self._istate[:] = 0
        self._window[:] = 0.0
        self._window[W_END] = math.nan

    def warm_up(self) -> None:
        """Load (or compile) the kernel now, on scratch copies: the state stays untouched, so
        a real-time caller's first tick does not wait for the compiler."""
        _measure_kernel(0.0, self._x.copy(), self._par, self._state.copy(),
                        self._istate.copy(), self._ring.copy(), self._noise, self._window.copy(),
                        self._window_s, self._out.copy(), self._fresh.copy())

    def measure(self, time_s: float, sample: object) -> Measured:
        """The measurements at ``time_s`` [s] (not before the last call's) of ``sample``, any
        object with the ``RigSample`` fields named in ``CHANNELS`` (SI). A time that is not
        finite or goes back, or a value that is not finite, raises ParameterError naming it,
        and the bank's state is unchanged."""
        time_s = float(time_s)
        if not time_s >= self._last_time_s or math.isinf(time_s):
            raise ParameterError(f"sensor time {time_s!r} s: expected a finite time not before "
                                 f"the last call's ({self._last_time_s:g} s); the sensors' "
                                 "state is unchanged")
        values = [getattr(sample, name) for name in _SAMPLE_FIELDS]
        for name, v in zip(_SAMPLE_FIELDS, values, strict=True):
            if not math.isfinite(v):
                raise ParameterError(f"exact {name} = {v!r}: expected a finite number; the "
                                     "sensors' state is unchanged")
        self._x[:len(values)] = values
        return self._measure(time_s)

    def _measure(self, time_s: float) -> Measured:
        self._last_time_s = time_s
        refill = _measure_kernel(time_s, self._x, self._par, self._state, self._istate,
                                 self._ring, self._noise, self._window, self._window_s,
                                 self._out, self._fresh)
        if refill:
            self._refill()
        return Measured(time_s, *self._out.tolist(), tuple(self._fresh.tolist()))

    def _refill(self) -> None:
        for c, rng in enumerate(self._rngs):
            if self._istate[c, I_NOISE] >= NOISE_BLOCK:
                rng.standard_normal(out=self._noise[c])
                self._istate[c, I_NOISE] = 0

    def measure_series(self, time_s: np.ndarray, columns: dict[str, np.ndarray]
                       ) -> dict[str, np.ndarray]:
        """Offline: measure a whole time series (times [s] ascending, one exact array per
        channel of ``CHANNELS`` but the severity), continuing from the bank's state, as calls
        of ``measure`` would; returns one measured array per channel and ``fresh_<channel>``
        flags. Compiled: the rows run in the kernel, Python only refills noise blocks."""
        times = np.ascontiguousarray(time_s, dtype=np.float64)
        n = len(times)
        inputs = np.zeros((n, len(CHANNELS)))
        for i, c in enumerate(_SAMPLE_FIELDS):
            inputs[:, i] = columns[c]
            if not np.isfinite(inputs[:, i]).all():
                k = int(np.flatnonzero(~np.isfinite(inputs[:, i]))[0])
                raise ParameterError(f"exact {c} = {float(inputs[k, i])!r} at row {k}: expected "
                                     "finite numbers; the sensors' state is unchanged")
        if n and not (np.isfinite(times).all() and times[0] >= self._last_time_s
                      and (np.diff(times) >= 0).all()):
            raise ParameterError("sensor times: expected finite times in ascending order, "
                                 f"not before the last call's ({self._last_time_s:g} s); the "
                                 "sensors' state is unchanged")
        out = np.empty((n, len(CHANNELS)))
        fresh = np.empty((n, len(CHANNELS)), dtype=np.bool_)
        k = 0
        while k < n:
            k = _series_kernel(k, times, inputs, self._par, self._state, self._istate,
                               self._ring, self._noise, self._window, self._window_s, out, fresh)
            self._refill()
        if n:
            self._out[:] = out[-1]
            self._last_time_s = float(times[-1])
        result = {c: out[:, i].copy() for i, c in enumerate(CHANNELS)}
        result.update({f"fresh_{c}": fresh[:, i].copy() for i, c in enumerate(CHANNELS)})
        return result


@nb.njit(cache=True)
def _series_kernel(k, times, inputs, par, st, ist, ring, noise, win, window_s, out, fresh):
    """Rows k... of a series through ``_measure_kernel``; returns the next row, early when a
    noise block must be refilled."""
    n = times.shape[0]
    while k < n:
        refill = _measure_kernel(times[k], inputs[k], par, st, ist, ring, noise, win, window_s,
                                 out[k], fresh[k])
        k += 1
        if refill:
            break
    return k


@nb.njit(cache=True)
def _measure_kernel(t, x, par, st, ist, ring, noise, win, window_s, out, fresh):
    """One call of every channel (module docstring); returns True when a channel's noise
    block is used up and must be refilled before the next call."""
    # the downhole severity of the exact bit speed, over consecutive windows
    w = x[_BIT_SPEED]
    if math.isnan(win[W_END]):
        win[W_END] = t + window_s
        win[W_MIN] = w
        win[W_MAX] = w
    elif t >= win[W_END] - 1e-9:
        mean = win[W_SUM] / win[W_N] if win[W_N] > 0 else w
        win[W_VALUE] = min(_severity_index(win[W_MAX], win[W_MIN], mean), SEVERITY_MAX)
        win[W_END] += window_s * (1.0 + math.floor((t - win[W_END]) / window_s))
        win[W_MIN] = w
        win[W_MAX] = w
        win[W_SUM] = 0.0
        win[W_N] = 0.0
    win[W_MIN] = min(win[W_MIN], w)
    win[W_MAX] = max(win[W_MAX], w)
    win[W_SUM] += w
    win[W_N] += 1.0
    x[_SEV] = win[W_VALUE]

    refill = False
    cap = ring.shape[1]
    eps = 1e-9 + 1e-12 * abs(t)
    for c in range(x.shape[0]):
        xc = x[c]
        period = par[c, P_PERIOD]
        tau = par[c, P_TAU]
        q = par[c, P_QUANTUM]
        fresh[c] = False
        if ist[c, I_INIT] == 0:                  # first call: steady before it
            ist[c, I_INIT] = 1
            st[c, S_Y] = xc
            st[c, S_T0] = t
            v0 = xc + par[c, P_BIAS]
            st[c, S_HELD] = np.round(v0 / q) * q if q > 0.0 else v0   # float: never overflows
        elif tau > 0.0:
            dt = t - st[c, S_LAST_T]
            st[c, S_Y] = st[c, S_PREV_X] + (st[c, S_Y] - st[c, S_PREV_X]) * math.exp(-dt / tau)
        else:
            st[c, S_Y] = xc
        st[c, S_PREV_X] = xc
        st[c, S_LAST_T] = t
        # sampling
        instant = st[c, S_T0] + ist[c, I_NEXT_K] * period if period > 0.0 else t
        if t >= instant - eps:
            v = st[c, S_Y] + par[c, P_BIAS]
            std = par[c, P_STD]
            if std > 0.0:
                v += std * noise[c, ist[c, I_NOISE]]
                ist[c, I_NOISE] += 1
                if ist[c, I_NOISE] >= noise.shape[1]:
                    refill = True
            if q > 0.0:                          # in floating point: round() is an int64 in
                v = np.round(v / q) * q          # numba, and 99.9 kN / 1e-15 overflowed it
            if period > 0.0:                     # the next instant after this call
                ist[c, I_NEXT_K] += 1 + math.floor((t - instant + eps) / period)
            if ist[c, I_COUNT] == cap:           # cannot happen at calls >= dt_s apart
                head = ist[c, I_HEAD]
                st[c, S_HELD] = ring[c, head, 1]
                fresh[c] = True
                ist[c, I_HEAD] = (head + 1) % cap
                ist[c, I_COUNT] -= 1
            tail = (ist[c, I_HEAD] + ist[c, I_COUNT]) % cap
            ring[c, tail, 0] = instant + par[c, P_DELAY]
            ring[c, tail, 1] = v
            ist[c, I_COUNT] += 1
        # release what has waited out its delay; the newest released is shown
        while ist[c, I_COUNT] > 0:
            head = ist[c, I_HEAD]
            if ring[c, head, 0] > t + eps:
                break
            st[c, S_HELD] = ring[c, head, 1]
            fresh[c] = True
            ist[c, I_HEAD] = (head + 1) % cap
            ist[c, I_COUNT] -= 1
        out[c] = st[c, S_HELD]
    return refill


# one call of a bank's channels on its arrays, for a caller that holds many banks' arrays
# stacked and calls it from compiled code (the vector environment)
measure_kernel = _measure_kernel
