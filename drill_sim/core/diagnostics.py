"""The rig node's /diagnostics status as a pure function of the rig's state and the tick
statistics, so the policy (what is OK, what warns, what is an error) is tested without ROS;
the node only turns the result into a ``diagnostic_msgs/DiagnosticArray`` (msg_docs/node.md).
"""

from __future__ import annotations

from dataclasses import dataclass

from .pacing import TickStats
from .rig import RigSample

OK, WARN, ERROR = 0, 1, 2      # the levels of diagnostic_msgs/DiagnosticStatus
SLOW_TICKS = 0.9               # warn below this fraction of rate_hz (once ticks overran)


@dataclass(frozen=True)
class Status:
    level: int                 # OK, WARN or ERROR
    message: str
    values: dict[str, str]     # key -> value, units in the keys


def regime(sample: RigSample, bounce_fraction: float) -> str:
    """The drilling regime in words: off bottom, bouncing (the bit left the rock within the
    window), stick-slip (the stick-slip flag is up) or drilling."""
    if sample.off_bottom:
        return "off bottom"
    if bounce_fraction > 0:
        return "bouncing"
    return "stick-slip" if sample.stick_slip else "drilling"


def rig_status(sample: RigSample, metrics: dict[str, float], ticks: TickStats, *,
               paused: bool, record_error: str | None, command_age_s: float,
               command_timeout_s: float, rate_hz: float, max_speed: bool,
               sim_time_s: float) -> Status:
    """The status over one diagnostics window. ERROR when recording failed; otherwise WARN
    when no command came for ``command_timeout_s`` [s] (not while paused) or, once ticks
    overran in real-time mode, when fewer than SLOW_TICKS of ``rate_hz`` [Hz] came; the
    message is the regime, or why it is not OK. ``metrics``: the rig's window metrics
    (``ssi``, ``stick_fraction``, ``bounce_fraction``); ``sim_time_s``: session time [s]."""
    name = regime(sample, metrics["bounce_fraction"])
    level, message = OK, name
    if record_error:
        level, message = ERROR, record_error
    elif paused:
        message = "paused"
    elif command_age_s > command_timeout_s:
        level = WARN
        message = (f"no command for {command_age_s:.1f} s (timeout {command_timeout_s:g} s); "
                   "holding the last valid command")
    elif ticks.overruns and not max_speed and ticks.ticks < SLOW_TICKS * rate_hz * ticks.wall_s:
        level, message = WARN, f"tick rate {ticks.rate_hz:.0f} Hz below {rate_hz:g} Hz"
    return Status(level, message, {
        "tick_rate_hz": f"{ticks.rate_hz:.1f}",
        "tick_period_p99_ms": f"{ticks.period_p99_s * 1e3:.3f}",
        "overruns": str(ticks.overruns),
        "real_time_factor": f"{ticks.real_time_factor:.3f}",
        "regime": name,
        "ssi": f"{metrics['ssi']:.3f}",
        "stick_fraction": f"{metrics['stick_fraction']:.3f}",
        "command_age_s": f"{command_age_s:.3f}",
        "sim_time_s": f"{sim_time_s:.3f}",
        "paused": str(paused).lower(),
    })
