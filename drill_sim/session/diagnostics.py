"""The rig node's /diagnostics status as a pure function of the rig's state and the tick
statistics, so the policy (what is OK, what warns, what is an error) is tested without ROS;
the node only turns the result into a ``diagnostic_msgs/DiagnosticArray`` (msg_docs/node.md).

Also the drilling regime in an engineer's words (``drilling_regime``), the one naming used by
/diagnostics and by the status line of ``drill_sim run``.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core.rig_sample import RigSample
from .lockstep import LockstepStatus
from .pacing import CATCH_UP_TICKS, TickStats, each_sampled

OK, WARN, ERROR = 0, 1, 2      # the levels of diagnostic_msgs/DiagnosticStatus
SLOW_TICKS = 0.9               # warn below this fraction of rate_hz (once ticks overran)

# Drilling regimes and their thresholds (msg_docs/node.md, "Drilling regimes")
STEADY, TORSIONAL, STICK_SLIP = "steady", "torsional oscillation", "stick-slip"
BOUNCING, OFF_BOTTOM, NOT_ROTATING = "bouncing", "off bottom", "not rotating"
REGIMES = (STEADY, TORSIONAL, STICK_SLIP, BOUNCING, OFF_BOTTOM, NOT_ROTATING)
TORSIONAL_SSI = 0.1            # bit speed swinging more than +-10 % around its mean
OFF_BOTTOM_FRACTION = 0.5      # off bottom now and for at least half of the window


def drilling_regime(*, ssi: float, stuck: bool, off_bottom_fraction: float,
                    off_bottom_now: bool, top_drive_speed_rad_s: float) -> str:
    """The bit's regime over a window, first match wins:

    - off bottom: off the rock now and for at least OFF_BOTTOM_FRACTION of the window;
    - bouncing: off the rock for part of the window (a single lift-off or landing also
      shows as bouncing for the one window that holds it);
    - not rotating: on the rock, stuck, and the top drive commanded to stand still;
    - stick-slip: the bit stopped (stuck) within the window;
    - torsional oscillation: SSI = (max - min) / (2 mean) of the bit speed >= TORSIONAL_SSI;
    - steady: otherwise (SSI below TORSIONAL_SSI, or no data: NaN).
    """
    if off_bottom_now and off_bottom_fraction >= OFF_BOTTOM_FRACTION:
        return OFF_BOTTOM
    if off_bottom_fraction > 0.0:
        return BOUNCING
    if stuck:
        return NOT_ROTATING if top_drive_speed_rad_s == 0.0 else STICK_SLIP
    return TORSIONAL if ssi >= TORSIONAL_SSI else STEADY


@dataclass(frozen=True)
class CommandCounts:
    """The node's command counters: taken since start, taken but replaced by a newer one of
    the same topic within the same tick, lost before they were taken (since start and in
    this window)."""

    received: int = 0
    superseded: int = 0
    lost: int = 0
    lost_in_window: int = 0
    # command topics with more than one publisher now: (topic, publishers' node names)
    shared: tuple[tuple[str, tuple[str, ...]], ...] = ()
    # command_owner first: commands refused since start, and each owned topic's owner node
    refused: int = 0
    owners: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class Status:
    level: int                 # OK, WARN or ERROR: the worst of the active conditions
    message: str               # every active condition, worst first; else the regime
    values: dict[str, str]     # key -> value, units in the keys


def shared_command_words(topic: str, publishers: tuple[str, ...],
                         owner: str | None = None) -> str:
    """What several programs commanding one rig mean (log and /diagnostics); ``owner``: the
    node whose commands alone are taken (``command_owner: first``)."""
    head = f"{len(publishers)} publishers on {topic}: {', '.join(publishers)}; "
    if owner is not None:
        return head + f"the rig takes only {owner}'s commands (command_owner first)"
    return head + ("the rig takes each one's commands as they come, so they override one "
                   "another: stop all but one, or start the rig with command_owner:=first")


def other_publishers_words(others: tuple[str, ...]) -> str:
    """What two publishers of one rig's samples mean, and what to do (log and /diagnostics)."""
    return (f"{len(others)} other publisher{'s' if len(others) > 1 else ''} on this rig's "
            f"~/joint_states ({', '.join(others)}): another rig of the same name or a replay "
            "onto its topics, so every subscriber gets both rigs' samples and commands reach "
            "both; stop it, or run this rig in its own namespace (-r __ns:=/rig2) or on "
            "another ROS_DOMAIN_ID")


def rig_status(sample: RigSample, metrics: dict[str, float], ticks: TickStats, *,
               paused: bool, record_error: str | None, command_age_s: float,
               command_timeout_s: float, rate_hz: float, max_speed: bool,
               sim_time_s: float, commands: CommandCounts = CommandCounts(),
               lockstep: LockstepStatus | None = None,
               real_time_factor: float = 1.0,
               other_publishers: tuple[str, ...] = (), every_tick_sampled: bool = False
               ) -> Status:
    """The status over one diagnostics window. Conditions: ERROR when recording failed;
    WARN, while running, when ticks overran in real-time mode and fewer than SLOW_TICKS of
    ``rate_hz`` [Hz] (the timer ticks expected to publish) came, when real-time ticks
    stalled in the window, when commands were lost in the window, when no command came for
    ``command_timeout_s`` [s], and in lockstep when a tick waited longer than its timeout;
    ``paused`` (OK) while paused. ``metrics``: the rig's window metrics (``ssi``,
    ``stick_fraction``, ``bounce_fraction``); ``sim_time_s``: session time [s];
    ``real_time_factor``: the one asked (a stall's ticks are published each at factors up
    to 1, ``pacing.each_sampled``); ``other_publishers``: the nodes other than this rig that
    publish on its samples' topic (another rig of the same name, a replay onto it), a WARN
    whether running or paused, since every subscriber then sees both; ``every_tick_sampled``:
    a stall's ticks each keep their sample however many (a scenario plays)."""
    name = drilling_regime(ssi=metrics["ssi"],
                           stuck=metrics["stick_fraction"] > 0.0 or sample.stick_slip,
                           off_bottom_fraction=metrics["bounce_fraction"],
                           off_bottom_now=sample.off_bottom,
                           top_drive_speed_rad_s=sample.top_drive_speed_rad_s)
    found: list[tuple[int, str]] = []
    if record_error:
        found.append((ERROR, record_error))
    if other_publishers:
        found.append((WARN, other_publishers_words(other_publishers)))
    if paused:
        found.append((OK, "paused"))
    else:
        if ticks.overruns and not max_speed and ticks.ticks < SLOW_TICKS * rate_hz * ticks.wall_s:
            found.append((WARN, f"tick rate {ticks.rate_hz:.0f} Hz below {rate_hz:g} Hz"))
        if ticks.stalls and not max_speed:
            # ticks the longest stall made due (rate_hz: the wake-ups expected a second)
            due = round(ticks.period_max_s * rate_hz * max(1.0, real_time_factor))
            if every_tick_sampled:
                how = ("each of their ticks published late (a scenario plays: every tick "
                       "keeps its sample)")
            elif real_time_factor > 1.0:
                how = (f"the longest advanced its {due} ticks with one sample (above "
                       "real-time factor 1 every wake-up advances its ticks with one)")
            elif each_sampled(due, real_time_factor):
                how = "their missed ticks published late"
            else:
                how = (f"the longest advanced its {due - 1} missed ticks with one sample (a "
                       f"stall of up to {CATCH_UP_TICKS} ticks publishes each, late)")
            found.append((WARN, f"{ticks.stalls} ticks stalled in the last {ticks.wall_s:.1f} s "
                                f"(longest {ticks.period_max_s * 1e3:.1f} ms); {how}"))
        if lockstep is not None and lockstep.waiting_s > lockstep.timeout_s:
            found.append((WARN, f"lockstep: waiting {lockstep.waiting_s:.1f} s for "
                                f"{', '.join(lockstep.missing)} stamped "
                                f"{lockstep.stamp_ns * 1e-9:.6f} s (timeout "
                                f"{lockstep.timeout_s:g} s)"))
        owners = dict(commands.owners)
        for topic, publishers in commands.shared:
            found.append((WARN, shared_command_words(topic, publishers, owners.get(topic))))
        if commands.lost_in_window:
            found.append((WARN, f"{commands.lost_in_window} commands lost in the last "
                                f"{ticks.wall_s:.1f} s (they came faster than the ticks)"))
        if command_age_s > command_timeout_s:
            found.append((WARN, f"no command for {command_age_s:.1f} s (timeout "
                                f"{command_timeout_s:g} s); holding the last valid command"
                          if commands.received else
                          f"no command received yet ({command_age_s:.1f} s since start, "
                          f"timeout {command_timeout_s:g} s); holding the initial commands"))
    found.sort(key=lambda c: -c[0])                 # worst first, stable otherwise
    return Status(max((c[0] for c in found), default=OK),
                  "; ".join(c[1] for c in found) if found else name, {
        "tick_rate_hz": f"{ticks.rate_hz:.1f}",
        "tick_period_p99_ms": f"{ticks.period_p99_s * 1e3:.3f}",
        "tick_period_max_ms": f"{ticks.period_max_s * 1e3:.3f}",
        "overruns": str(ticks.overruns),
        "longest_stall_ms": f"{ticks.longest_stall_s * 1e3:.3f}",
        "real_time_factor": f"{ticks.real_time_factor:.3f}",
        "regime": name,
        "ssi": f"{metrics['ssi']:.3f}",
        "stick_fraction": f"{metrics['stick_fraction']:.3f}",
        "off_bottom_fraction": f"{metrics['bounce_fraction']:.3f}",
        "command_age_s": f"{command_age_s:.3f}",
        "commands_received": str(commands.received),
        "commands_superseded": str(commands.superseded),
        "commands_lost": str(commands.lost),
        "command_topics_with_several_publishers": ",".join(t for t, _ in commands.shared),
        "commands_refused": str(commands.refused),
        "command_owners": ",".join(f"{t}={n}" for t, n in commands.owners),
        "sim_time_s": f"{sim_time_s:.3f}",
        "paused": str(paused).lower(),
    } | ({} if lockstep is None else {
        "lockstep_waiting_s": f"{lockstep.waiting_s:.3f}",
        "lockstep_other_stamps": str(lockstep.other_stamps),
    }))
