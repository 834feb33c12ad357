"""When the rig node's ticks are due, how many each timer tick advances, and the tick
statistics for /diagnostics. No ROS here, so the pacing is tested with a fake clock.

Simulated time moves in whole ticks of 1/``rate_hz`` in every mode (the step divides the tick,
``session.rules.step_s``), so every sample is stamped on that grid.
Real-time mode: the ticks due are those the wall clock times ``real_time_factor`` has reached
since an anchor, rounded to the nearest (the timer's jitter, under a quarter period, never
moves a tick); the anchor is set again at start, on resume, reset, a rate or factor change,
and when the rig fell more than 0.1 s of simulated time behind: that backlog is dropped rather
than caught up in a burst. A loop that wakes at ``next_tick_s`` advances one tick a wake-up at
factor 1 (every 1/``rate_hz``), two at factor 2, one every other period at 0.5; a wake-up the
machine delayed (a stall: more than 1.5 periods after the one before) advances the ticks it
missed at once, each with its own sample (``samples``) up to CATCH_UP_TICKS of them.
Max-speed and lockstep modes: each timer tick advances exactly one tick, back to back.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

BEHIND_S = 0.1           # simulated seconds per unit real-time factor before the backlog goes
OVERRUN_PERIODS = 1.5    # a tick later than this many periods is an overrun
# a stall of at most this many ticks still gives each tick its sample (published late, back
# to back: ~0.25 ms of CPU each at 1 kHz); a longer one advances its ticks with one sample
CATCH_UP_TICKS = 5


def each_sampled(ticks: int, real_time_factor: float = 1.0) -> bool:
    """Whether a real-time wake-up that made ``ticks`` due publishes a sample for each: the
    rule ``Pacer.samples`` follows and ``/diagnostics`` reports. Above factor 1 a wake-up
    advances ceil(factor) ticks by design, with one sample."""
    return ticks <= CATCH_UP_TICKS and real_time_factor <= 1.0


@dataclass(frozen=True)
class TickStats:
    """The ticks of one diagnostics window."""

    ticks: int               # ticks that advanced the rig
    wall_s: float            # window length [s], > 0
    sim_s: float             # simulated time advanced [s]
    period_p99_s: float      # 99th percentile of the timer's periods [s]; nan without any
    overruns: int            # since start: real-time ticks later than OVERRUN_PERIODS (stalls)
    period_max_s: float = math.nan   # the longest period [s]; nan without any
    stalls: int = 0          # overruns (stalls) in this window
    longest_stall_s: float = 0.0     # the longest stalled period since start [s]; 0: none

    @property
    def rate_hz(self) -> float:
        return self.ticks / self.wall_s

    @property
    def real_time_factor(self) -> float:
        return self.sim_s / self.wall_s


class Pacer:
    """The node's clock discipline: ``tick_started`` on every timer tick, ``due`` and
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
        self.longest_stall_s = 0.0
        self._overruns_before = 0
        self._last_tick: float | None = None
        self.anchor()
        self._window = (self._clock(), 0, rig_time_s)    # wall, ticks, rig time at its start

    def configure(self, rate_hz: float, real_time_factor: float, max_speed: bool) -> None:
        """New settings at run time; a new rate or real-time factor counts from now."""
        if (rate_hz, real_time_factor) != (self.rate_hz, self.real_time_factor):
            self.anchor()
        self.rate_hz, self.real_time_factor, self.max_speed = rate_hz, real_time_factor, max_speed
        if self._buffer_size(rate_hz) > self._periods.size:
            grown = np.zeros(self._buffer_size(rate_hz))
            grown[:self._n_periods] = self._periods[:self._n_periods]
            self._periods = grown

    def anchor(self) -> None:
        """Real time counts again from the next timer tick, which advances the ticks of one
        timer period (one at factor 1): so the grid of due ticks follows the timer's phase."""
        self._anchored = False

    def reset(self, rig_time_s: float) -> None:
        """The rig was reset to ``rig_time_s``: anchor again, and measure this window's
        simulated time from there."""
        self.anchor()
        self._window = (self._window[0], self._window[1], rig_time_s)

    def _buffer_size(self, rate_hz: float) -> int:
        """Room for the periods of a window, four times over (diagnostics may come late)."""
        return int(4 * rate_hz * self._window_s) + 8

    @property
    def tick_s(self) -> float:
        """Simulated time of one tick [s] in every mode (what ``~/step`` advances)."""
        return 1.0 / self.rate_hz

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
                self.longest_stall_s = max(self.longest_stall_s, period)
        self._last_tick = now

    def due(self) -> int:
        """How many whole ticks this timer tick advances: one at max speed (and in lockstep);
        in real time those due by the wall clock, at most BEHIND_S of simulated time (times
        the real-time factor) plus one tick; a larger backlog is dropped (anchored again)."""
        if self.max_speed:
            return 1
        now = self._clock()
        per_wall_s = self.real_time_factor * self.rate_hz         # ticks a wall second
        if not self._anchored:
            self._wall0, self._done, self._anchored = now - 1.0 / self.rate_hz, 0, True
        due = math.floor((now - self._wall0) * per_wall_s + 0.5) - self._done
        limit = math.ceil(BEHIND_S * per_wall_s) + 1
        if due > limit:
            self.anchor()
            return limit
        self._done += max(due, 0)
        return max(due, 0)

    def next_tick_s(self) -> float:
        """When the loop should wake next [s, the clock's]: the middle of the rounding window
        of the tick that comes at least a period (1/``rate_hz`` of wall time) after the last,
        so a wake-up there, early or late by up to half a tick, advances exactly the ticks of
        a period: one at factors up to 1 (at 0.5 a wake-up every 2 periods), ceil(factor)
        above. A loop that sleeps until this stays in phase with the grid of due ticks (a loop
        with a grid of its own drifts off it after a late wake-up, and jitter around a
        rounding edge then advances 0 ticks, then 2, publishing one sample for both). Now when
        not anchored (the next call of ``due`` anchors) and at max speed."""
        if self.max_speed or not self._anchored:
            return self._clock()
        per_wall_s = self.real_time_factor * self.rate_hz
        return self._wall0 + (self._done + max(1, math.ceil(self.real_time_factor - 1e-9))
                              ) / per_wall_s

    def samples(self, ticks: int) -> tuple[int, ...]:
        """How a wake-up advances the ``ticks`` that ``due`` gave: the ticks of each sample
        it publishes. At real-time factors up to 1 each tick has its sample, also after a
        stall of up to CATCH_UP_TICKS ticks (published late, back to back, as a rig's logger
        keeps every sample while its link lags): so a stall leaves no gap in the samples,
        the sensors and the recording, and the run is the one an undelayed machine gives with
        the same commands. Above factor 1 (ceil(factor) ticks a wake-up by design), at max
        speed and after a longer stall, one sample for all."""
        if ticks <= 1 or self.max_speed or not each_sampled(ticks, self.real_time_factor):
            return (ticks,) if ticks > 0 else ()
        return (1,) * ticks

    def advanced(self, ticks: int = 1) -> None:
        """The rig advanced by ``ticks`` ticks and published one sample."""
        self.ticks += 1 if ticks > 0 else 0

    def window(self, rig_time_s: float) -> TickStats:
        """The statistics since the last window (or the start); a new window starts."""
        now = self._clock()
        wall0, ticks0, sim0 = self._window
        periods = self._periods[:self._n_periods]
        p99 = float(np.percentile(periods, 99)) if periods.size else math.nan
        longest, self._longest = self._longest, math.nan
        self._n_periods = 0
        self._window = (now, self.ticks, rig_time_s)
        stalls, self._overruns_before = self.overruns - self._overruns_before, self.overruns
        return TickStats(self.ticks - ticks0, max(now - wall0, 1e-9), rig_time_s - sim0, p99,
                         self.overruns, longest, stalls, self.longest_stall_s)
