"""The drive's effort and the settling of a run: the figures a controls engineer weighs beside
the vibration ones (msg_docs/control.md, "Effort and settling").

One definition for every tool that scores a run (``drill_sim control``, ``drill_sim bag
metrics``, the main job's summary), with the same names in every JSON (``EFFORT_KEYS``).
``EffortStats`` takes the samples a chunk at a time and keeps a few sums plus one small record
per ``BLOCK_S`` of bit speed, so a bag of any length is scored in bounded memory:

- ``motor_torque_rms_nm``: RMS of the applied motor torque's deviation from its window mean;
- ``motor_torque_p2p_nm``: its max − min;
- ``torque_rate_rms_nm_s``: RMS of its rate between consecutive samples;
- ``time_at_torque_limit_fraction``: share of samples with the torque on one of the drive's
  limits (None: no limits, a kinematic drive);
- ``drive_energy_j``: the motor's work ∫ T_m Ω_TD dt (trapezoidal; braking counts negative);
- ``settling_time_s``: from the last controller switch or set-point step in the window, the
  time until the SSI of the bit speed over every later ``SETTLING_WINDOW_S`` window stays at
  or below ``SETTLING_SSI`` (None: no such event, or not settled before the end).

Motor figures are None when the run has no motor torque (a bag without the drive's topic).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

EFFORT_KEYS = ("motor_torque_rms_nm", "motor_torque_p2p_nm", "torque_rate_rms_nm_s",
               "time_at_torque_limit_fraction", "drive_energy_j", "settling_time_s")
SETTLING_WINDOW_S = 4.0        # longer than a stick-slip period of the shipped strings
SETTLING_SSI = 0.5             # bit speed within ±50 % of its mean over the window: far from a stop
BLOCK_S = 0.05                 # resolution of the settling time [s]
LIMIT_TOLERANCE = 1e-9         # of the drive's torque span: "on the limit"

Figures = dict[str, float | None]


class EffortStats:
    """Effort and settling of one run, fed in time order with ``add``; ``result()`` gives the
    ``EFFORT_KEYS``. ``torque_limits_nm``: the drive's (min, max) motor torque [N·m], None
    without limits; ``events_s``: controller switches and set-point steps [s, same clock as
    the samples' times]. Samples before ``window_start_s`` [s] count for the settling only
    (a run settles from its switch, before the metrics window of an evaluation)."""

    def __init__(self, torque_limits_nm: tuple[float, float] | None = None,
                 events_s: Iterable[float] = (), window_start_s: float = -math.inf) -> None:
        self.limits = torque_limits_nm
        self.window_start_s = window_start_s
        self.events_s = sorted(float(e) for e in events_s if math.isfinite(e))
        self.start_s = math.nan
        self.end_s = math.nan
        self.n = 0
        self.mean = 0.0                 # running mean and sum of squared deviations (Welford,
        self.m2 = 0.0                   # combined chunk by chunk)
        self.low = math.inf
        self.high = -math.inf
        self.at_limit = 0
        self.rate_sq = 0.0
        self.rates = 0
        self.energy_j = 0.0
        self.last: tuple[float, float, float] | None = None   # t, torque, speed
        self.blocks: dict[int, list[float]] = {}              # k -> [max, min, sum, n]

    def add(self, time_s: np.ndarray, bit_speed_rad_s: np.ndarray,
            motor_torque_nm: np.ndarray | None = None,
            top_drive_speed_rad_s: np.ndarray | None = None) -> None:
        """Samples in time order; a non-finite torque is left out (not measured there)."""
        t = np.asarray(time_s, float)
        if t.size == 0:
            return
        if not math.isfinite(self.start_s):
            self.start_s = float(t[0])
        self.end_s = float(t[-1])
        self._add_speed(t, np.asarray(bit_speed_rad_s, float))
        if motor_torque_nm is None:
            return
        torque = np.asarray(motor_torque_nm, float)
        speed = (np.full(t.size, np.nan) if top_drive_speed_rad_s is None
                 else np.asarray(top_drive_speed_rad_s, float))
        ok = np.isfinite(torque) & (t >= self.window_start_s)
        t, torque, speed = t[ok], torque[ok], speed[ok]
        if t.size == 0:
            return
        n, mean = t.size, float(torque.mean())
        m2 = float(np.sum((torque - mean) ** 2))
        total = self.n + n
        delta = mean - self.mean
        self.mean += delta * n / total
        self.m2 += m2 + delta * delta * self.n * n / total
        self.n = total
        self.low = min(self.low, float(torque.min()))
        self.high = max(self.high, float(torque.max()))
        if self.limits is not None:
            lo, hi = self.limits
            tol = LIMIT_TOLERANCE * (hi - lo)
            self.at_limit += int(np.count_nonzero((torque >= hi - tol) | (torque <= lo + tol)))
        if self.last is not None:
            t = np.concatenate(([self.last[0]], t))
            torque = np.concatenate(([self.last[1]], torque))
            speed = np.concatenate(([self.last[2]], speed))
        dt = np.diff(t)
        step = dt > 0.0
        rate = np.diff(torque)[step] / dt[step]
        self.rate_sq += float(np.sum(rate * rate))
        self.rates += rate.size
        power = torque * speed
        self.energy_j += float(np.sum(0.5 * (power[1:] + power[:-1]) * dt))
        self.last = (float(t[-1]), float(torque[-1]), float(speed[-1]))

    def _add_speed(self, t: np.ndarray, w: np.ndarray) -> None:
        ok = np.isfinite(w)
        t, w = t[ok], w[ok]
        if t.size == 0:
            return
        k = np.floor((t - self.start_s) / BLOCK_S).astype(np.int64)
        starts = np.r_[0, np.flatnonzero(np.diff(k)) + 1]
        highs = np.maximum.reduceat(w, starts)
        lows = np.minimum.reduceat(w, starts)
        sums = np.add.reduceat(w, starts)
        sizes = np.diff(np.r_[starts, k.size])
        for key, hi, lo, total, size in zip(k[starts].tolist(), highs.tolist(), lows.tolist(),
                                            sums.tolist(), sizes.tolist(), strict=True):
            block = self.blocks.get(key)
            if block is None:
                self.blocks[key] = [hi, lo, total, size]
            else:
                block[0], block[1] = max(block[0], hi), min(block[1], lo)
                block[2] += total
                block[3] += size

    def settling_time_s(self) -> float | None:
        """From the last event in the run to the start of the first window after which every
        ``SETTLING_WINDOW_S`` window has SSI <= ``SETTLING_SSI``; None when it never does."""
        events = [e for e in self.events_s if self.start_s <= e < self.end_s]
        if not events:
            return None
        first = math.ceil((events[-1] - self.start_s) / BLOCK_S - 1e-9)
        width = round(SETTLING_WINDOW_S / BLOCK_S)
        last = math.floor((self.end_s - self.start_s) / BLOCK_S + 1e-9)
        count = last - first - width + 1       # windows of whole blocks after the event
        if count < 1:
            return None
        rows = np.zeros((last - first, 4))
        rows[:, 0], rows[:, 1] = -np.inf, np.inf
        for k in range(first, last):
            if k in self.blocks:
                rows[k - first] = self.blocks[k]
        view = np.lib.stride_tricks.sliding_window_view
        high = view(rows[:, 0], width)[:count].max(axis=1)
        low = view(rows[:, 1], width)[:count].min(axis=1)
        n = view(rows[:, 3], width)[:count].sum(axis=1)
        mean = view(rows[:, 2], width)[:count].sum(axis=1) / np.where(n > 0, n, 1.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            ssi = np.where((n > 0) & (mean > 0.0), (high - low) / (2.0 * mean), np.inf)
        unsettled = np.flatnonzero(~(ssi <= SETTLING_SSI))
        settled_from = 0 if unsettled.size == 0 else int(unsettled[-1]) + 1
        if settled_from >= count:
            return None
        return round((first + settled_from) * BLOCK_S + self.start_s - events[-1], 9)

    def result(self) -> Figures:
        """The ``EFFORT_KEYS`` (None where a figure does not apply)."""
        motor = self.n > 0
        out: Figures = {
            "motor_torque_rms_nm": math.sqrt(self.m2 / self.n) if motor else None,
            "motor_torque_p2p_nm": self.high - self.low if motor else None,
            "torque_rate_rms_nm_s": (math.sqrt(self.rate_sq / self.rates)
                                     if self.rates else None),
            "time_at_torque_limit_fraction": (self.at_limit / self.n
                                              if motor and self.limits is not None else None),
            "drive_energy_j": (self.energy_j if motor and math.isfinite(self.energy_j)
                               else None),
            "settling_time_s": self.settling_time_s(),
        }
        return out


def effort_figures(time_s: np.ndarray, bit_speed_rad_s: np.ndarray,
                   motor_torque_nm: np.ndarray | None = None,
                   top_drive_speed_rad_s: np.ndarray | None = None, *,
                   torque_limits_nm: tuple[float, float] | None = None,
                   events_s: Iterable[float] = (),
                   window_start_s: float = -math.inf) -> Figures:
    """``EffortStats`` over one run's whole arrays."""
    stats = EffortStats(torque_limits_nm, events_s, window_start_s)
    stats.add(time_s, bit_speed_rad_s, motor_torque_nm, top_drive_speed_rad_s)
    return stats.result()
