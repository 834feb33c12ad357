"""When the rig node's ticks are due, how far each advances the rig, and the tick statistics
for /diagnostics. No ROS here, so the pacing is tested with a fake clock.

Real-time mode: simulated time follows the wall clock times ``real_time_factor`` from an
anchor, set again at start, on resume, reset and a factor change, and when the rig fell more
than 0.1 s of simulated time behind: that backlog is dropped rather than caught up in a burst.
Max-speed mode (``max_speed`` with ``/clock``): each tick advances 1/``rate_hz`` of simulated
time, back to back. Times are rig times [s] (``Rig.time_s``, which restarts on reset).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

BEHIND_S = 0.1           # simulated seconds per unit real-time factor before the backlog goes
OVERRUN_PERIODS = 1.5    # a tick later than this many periods is an overrun


@dataclass(frozen=True)
class TickStats:
    """The ticks of one diagnostics window."""

    ticks: int               # ticks that advanced the rig
    wall_s: float            # window length [s], > 0
    sim_s: float             # simulated time advanced [s]
    period_p99_s: float      # 99th percentile of the timer's periods [s]; nan without any
    overruns: int            # since start
    period_max_s: float = math.nan   # the longest period [s]; nan without any

    @property
    def rate_hz(self) -> float:
        return self.ticks / self.wall_s

    @property
    def real_time_factor(self) -> float:
        return self.sim_s / self.wall_s


class Pacer:
    """The node's clock discipline: ``tick_started`` on every timer tick, ``target`` and
    ``advanced`` around each advance of the rig, ``window`` once per diagnostics period.

    window_s: the diagnostics period [s], which sizes the buffer of tick periods; clock: the
    wall clock [s] (monotonic)."""

    def __init__(self, rate_hz: float, real_time_factor: float, max_speed: bool,
                 window_s: float, rig_time_s: float,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.rate_hz, self.real_time_factor, self.max_speed = rate_hz, real_time_factor, max_speed
        self._clock = clock
        self._window_s = window_s
        self._periods = np.zeros(self._buffer_size(rate_hz))
        self._n_periods = 0
        self._longest = math.nan
        self.overruns = self.ticks = 0
        self._last_tick: float | None = None
        self._target = rig_time_s
        self.anchor(rig_time_s)
        self._window = (self._wall0, 0, rig_time_s)      # wall, ticks, rig time at its start

    def configure(self, rate_hz: float, real_time_factor: float, max_speed: bool,
                  rig_time_s: float) -> None:
        """New settings at run time; a new real-time factor counts from now."""
        changed_factor = real_time_factor != self.real_time_factor
        self.rate_hz, self.real_time_factor, self.max_speed = rate_hz, real_time_factor, max_speed
        if self._buffer_size(rate_hz) > self._periods.size:
            grown = np.zeros(self._buffer_size(rate_hz))
            grown[:self._n_periods] = self._periods[:self._n_periods]
            self._periods = grown
        if changed_factor:
            self.anchor(rig_time_s)

    def anchor(self, rig_time_s: float) -> None:
        """Simulated time ``rig_time_s`` is now: real time counts from here."""
        self._wall0, self._sim0 = self._clock(), rig_time_s

    def reset(self, rig_time_s: float) -> None:
        """The rig was reset to ``rig_time_s``: anchor there, and measure this window's
        simulated time from there."""
        self.anchor(rig_time_s)
        self._window = (self._window[0], self._window[1], rig_time_s)

    def _buffer_size(self, rate_hz: float) -> int:
        """Room for the periods of a window, four times over (diagnostics may come late)."""
        return int(4 * rate_hz * self._window_s) + 8

    @property
    def tick_s(self) -> float:
        """Simulated time of one nominal tick [s] (what ``~/step`` advances): 1/``rate_hz``
        times the real-time factor in real time, 1/``rate_hz`` at max speed."""
        return 1.0 / self.rate_hz * (1.0 if self.max_speed else self.real_time_factor)

    def tick_started(self) -> None:
        """Every timer tick, paused or not: the period since the last one."""
        now = self._clock()
        if self._last_tick is not None:
            period = now - self._last_tick
            if self._n_periods < self._periods.size:
                self._periods[self._n_periods] = period
                self._n_periods += 1
            if not period <= self._longest:          # also replaces NaN
                self._longest = period
            if period > OVERRUN_PERIODS / self.rate_hz and not self.max_speed:
                self.overruns += 1
        self._last_tick = now

    def target(self, rig_time_s: float) -> float:
        """The rig time to advance to in this tick [s], never more than BEHIND_S times the
        real-time factor (plus a tick) ahead of ``rig_time_s``."""
        if self.max_speed:
            self._target = rig_time_s + 1.0 / self.rate_hz
        else:
            self._target = self._sim0 + (self._clock() - self._wall0) * self.real_time_factor
        return min(self._target, rig_time_s + BEHIND_S * self.real_time_factor
                   + 1.0 / self.rate_hz)

    def advanced(self, rig_time_s: float) -> None:
        """The tick advanced the rig to ``rig_time_s``: count it, drop a backlog."""
        if self._target - rig_time_s > BEHIND_S * self.real_time_factor:
            self.anchor(rig_time_s)
        self.ticks += 1

    def window(self, rig_time_s: float) -> TickStats:
        """The statistics since the last window (or the start); a new window starts."""
        now = self._clock()
        wall0, ticks0, sim0 = self._window
        periods = self._periods[:self._n_periods]
        p99 = float(np.percentile(periods, 99)) if periods.size else math.nan
        longest, self._longest = self._longest, math.nan
        self._n_periods = 0
        self._window = (now, self.ticks, rig_time_s)
        return TickStats(self.ticks - ticks0, max(now - wall0, 1e-9), rig_time_s - sim0, p99,
                         self.overruns, longest)
