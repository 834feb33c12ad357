"""The controller node's loop without ROS: the readings of one rig tick joined by their stamp,
the law stepped on simulated time (a gap caught up, a repeated tick answered again), and the
status a controller reports. The node only feeds it messages and publishes what it returns.
"""

from __future__ import annotations

import math

from .laws import SurfaceMeasurement
from .supervisor import Supervisor

MAX_CATCH_UP = 100            # law steps for one sample after a gap in the stamps
KEEP_PENDING = 16             # incomplete stamps kept; beyond, the oldest are forgotten
SPEED, MOTOR, SURFACE, SETPOINT = range(4)     # a reading's place in a sample


class SampledLoop:
    """Readings in (speed [rad/s], motor and surface torque [N·m], and with ``with_setpoint``
    the set-point [rad/s] stamped for that tick), one law step per complete stamp out."""

    def __init__(self, with_setpoint: bool = False) -> None:
        self.size = 4 if with_setpoint else 3
        self._pending: dict[int, list[float | None]] = {}
        self.last: SurfaceMeasurement | None = None

    def put(self, stamp_ns: int, place: int, value: float) -> list[float] | None:
        """One reading of the tick stamped ``stamp_ns`` [ns]; the tick's readings once all are
        in (older incomplete ticks are then dropped: a reading that never came), else None."""
        slot = self._pending.get(stamp_ns)
        if slot is None:
            if len(self._pending) > KEEP_PENDING:
                for old in sorted(self._pending)[:-KEEP_PENDING // 2]:
                    del self._pending[old]
            slot = self._pending[stamp_ns] = [None] * self.size
        slot[place] = value
        if None in slot:
            return None
        for old in [s for s in self._pending if s <= stamp_ns]:   # this tick and older
            del self._pending[old]
        return slot  # type: ignore[return-value]

    def step(self, core: Supervisor, stamp_ns: int, readings: list[float]
             ) -> tuple[float | None, str]:
        """The torque command [N·m] for the tick (None: nothing to publish) and, when the tick
        was skipped, why. A tick seen again gets the same answer; after a gap in the stamps the
        law is stepped once per period h of the gap on readings interpolated linearly from the
        previous tick (at most MAX_CATCH_UP steps), so its filters, derivative and integral
        keep their time and see no jump."""
        if not all(math.isfinite(v) for v in readings):
            return None, f"sample at {stamp_ns * 1e-9:.3f} s skipped: non-finite input"
        if self.size == 4:                           # this tick's set-point, before its step
            core.set_speed(readings[SETPOINT])
        m = SurfaceMeasurement(stamp_ns * 1e-9, *readings[:3])
        last = self.last
        if last is not None and m.time_s == last.time_s:
            again = core.last_output is not None and core.enabled
            return (core.last_output if again else None), ""
        self.last = m
        periods = 1 if last is None else round((m.time_s - last.time_s) / core.h_s)
        periods = min(max(periods, 1), MAX_CATCH_UP)
        for k in range(1, periods):
            f = k / periods
            core.step(SurfaceMeasurement(*(a + f * (b - a) for a, b in zip(last, m, strict=True))))
        return core.step(m), ""


def controller_status(core: Supervisor, window: dict[str, float], period_known: bool,
                      rig: str) -> tuple[bool, str]:
    """(warn, words) for a controller's status over ``window`` (``Supervisor.take_window``)."""
    if not period_known:
        return True, f"waiting for {rig}'s rate_hz"
    if not core.enabled:
        return False, "disabled"
    if window["samples"] == 0:
        return True, "no samples: the rig's inputs are not arriving"
    if window["saturation_fraction"] > 0.5 or window["windup_fraction"] > 0.5:
        return True, "output saturated"
    return False, "controlling"
