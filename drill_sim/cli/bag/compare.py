"""``drill_sim bag compare A B [C ...]``: sessions overlaid against time from their first sample
(bit and top-drive speed with the speed set-points, WOB, torques on bit and at the surface,
motor torque against the drive's limits), their recorded events marked, and a table of their
metrics and effort side by side with each one's difference from the first bag."""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...bag.bag import Bag
from ...bag.errors import BagError
from ...bag.series import RigSeries, joint_topic
from ...bag.session_events import SessionEvents, read_session, speed_setpoints
from ...core import RPM
from ...core.effort import EFFORT_KEYS
from ..checks import in_range, number, plot_file
from ..errors import UsageError

HELP = "two or more sessions overlaid, events marked, metrics and effort side by side"
# (key, heading, scale to the shown unit, format)
TABLE = (("ssi", "SSI", 1.0, ".3f"), ("stick_fraction", "stick fraction", 1.0, ".3f"),
         ("mean_bit_speed_rad_s", "mean bit speed [rpm]", 1 / RPM, ".1f"),
         ("mean_wob_n", "mean WOB [kN]", 1e-3, ".1f"),
         ("mean_tob_nm", "mean TOB [kN m]", 1e-3, ".2f"),
         ("mean_rop_m_s", "mean ROP [m/h]", 3600.0, ".2f"),
         ("motor_torque_rms_nm", "motor torque rms [kN m]", 1e-3, ".3f"),
         ("motor_torque_p2p_nm", "motor torque p2p [kN m]", 1e-3, ".2f"),
         ("torque_rate_rms_nm_s", "torque rate rms [kN m/s]", 1e-3, ".1f"),
         ("time_at_torque_limit_fraction", "time at torque limit", 1.0, ".3f"),
         ("drive_energy_j", "drive energy [MJ]", 1e-6, ".3f"),
         ("settling_time_s", "settling time [s]", 1.0, ".2f"),
         ("duration_s", "duration [s]", 1.0, ".2f"))


@dataclass
class Session:
    """One bag's series (time from its first sample), figures and events."""

    path: Path
    series: RigSeries
    figures: dict[str, float | None]
    events: SessionEvents
    motor_torque_nm: np.ndarray | None
    setpoint_s: np.ndarray
    setpoint_rad_s: np.ndarray

    @property
    def t(self) -> np.ndarray:
        return self.series.time_s - self.series.time_s[0]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("bags", type=Path, nargs="+", metavar="BAG",
                        help="two or more bag directories or .mcap files")
    parser.add_argument("--out", type=Path, default=Path("compare.png"),
                        help="figure (default compare.png)")
    parser.add_argument("--json", action="store_true",
                        help="the table as one JSON object on stdout")
    parser.add_argument("--start", type=number, default=0.0, metavar="S",
                        help="the figures from S seconds after each session's first sample "
                             "(default 0: all of it; the settling counts from the switch)")


def load(path: Path, start_s: float = 0.0) -> Session:
    """A bag's session: its rig series in memory (memory grows with the bag), figures,
    events and speed set-points."""
    with Bag.open(path) as bag:
        name = joint_topic(bag, None)
        problems: list[str] = []
        read = read_session(bag, window_start_s=start_s, problems=problems)
        series = read.series
        if series.time_s.size < 2:
            raise BagError(f"{path}: fewer than two samples on {name}")
        shown = series.window(start_s, None) if start_s > 0.0 else series
        if shown.time_s.size < 2:
            raise BagError(f"{path}: fewer than two samples from --start {start_s:g} s on")
        figures: dict[str, float | None] = dict(shown.metrics())
        figures.update(read.effort)
        stamps, speeds = speed_setpoints(bag, name)
    for problem in dict.fromkeys(problems):      # damage: what was readable is compared
        print(f"drill_sim bag compare: {path}: {problem}", file=sys.stderr)
    origin = round(series.time_s[0] * 1e9)
    return Session(path, series, figures, read.events, read.motor_torque_nm,
                   (stamps - origin) / 1e9, speeds)


def run(args: argparse.Namespace) -> int:
    if len(args.bags) < 2:
        raise UsageError(f"bag compare: {len(args.bags)} bag given; expected two or more")
    seen: set[Path] = set()
    for bag in args.bags:                     # the figures are keyed by bag: each once
        if (where := Path(bag).resolve()) in seen:
            raise UsageError(f"bag compare: {bag} given twice; expected each bag once")
        seen.add(where)
    plot_file("--out", args.out)
    start = in_range("--start", args.start, 0.0, 1e9, unit="s", what="a time")
    sessions = [load(p, start) for p in args.bags]
    table = {str(s.path): {k: s.figures.get(k) for k, *_ in TABLE} for s in sessions}
    first = sessions[0].figures
    differences = {str(s.path): {k: _difference(s.figures.get(k), first.get(k))
                                 for k, *_ in TABLE} for s in sessions[1:]}
    _plot(args.out, sessions)
    if args.json:
        events = {str(s.path): [{"time_s": (ns - round(s.series.time_s[0] * 1e9)) / 1e9,
                                 "event": kind, **values} for ns, kind, values in s.events.events]
                  for s in sessions}
        print(json.dumps({"bags": table, "differences_from_first": differences,
                          "events": events,
                          "units": {"ssi": "-", "stick_fraction": "-",
                                    "mean_bit_speed_rad_s": "rad/s", "mean_wob_n": "N",
                                    "mean_tob_nm": "N m", "mean_rop_m_s": "m/s",
                                    "duration_s": "s", **_effort_units()},
                          "plot": str(args.out)}))
        return 0
    for k, s in enumerate(sessions):
        print(f"[{k}] {s.path}")
    heads = [f"[{k}]" for k in range(len(sessions))] + \
            [f"[{k}]-[0]" for k in range(1, len(sessions))]
    print(f"{'':<26}" + "".join(f"{h:>12}" for h in heads))
    for key, label, scale, fmt in TABLE:
        values = [s.figures.get(key) for s in sessions]
        diffs = [_difference(v, values[0]) for v in values[1:]]
        print(f"{label:<26}" + "".join(
            f"{'-' if v is None else format(v * scale, fmt):>12}" for v in values + diffs))
    print(f"plot written to {args.out}")
    return 0


def _difference(value: float | None, first: float | None) -> float | None:
    if value is None or first is None or not (math.isfinite(value) and math.isfinite(first)):
        return None
    return value - first


def _effort_units() -> dict[str, str]:
    units = {"motor_torque_rms_nm": "N m", "motor_torque_p2p_nm": "N m",
             "torque_rate_rms_nm_s": "N m/s", "time_at_torque_limit_fraction": "-",
             "drive_energy_j": "J", "settling_time_s": "s"}
    assert set(units) == set(EFFORT_KEYS)
    return units


def _plot(path: Path, sessions: list[Session]) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(11, 10), constrained_layout=True)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    limits = set()
    labels = 0
    for k, s in enumerate(sessions):
        c, name, t = colors[k % len(colors)], s.path.name, s.t
        axes[0].plot(t, s.series.bit_speed_rad_s / RPM, color=c, lw=0.8, label=f"{name}: bit")
        axes[0].plot(t, s.series.top_drive_speed_rad_s / RPM, color=c, lw=0.6, ls="--",
                     label=f"{name}: top drive")
        if s.setpoint_s.size:
            ends = np.r_[s.setpoint_s, t[-1]]
            axes[0].step(ends, np.r_[s.setpoint_rad_s, s.setpoint_rad_s[-1]] / RPM, where="post",
                         color=c, lw=1.2, ls=":", label=f"{name}: set-point")
        axes[1].plot(t, s.series.wob_n / 1e3, color=c, lw=0.8, label=name)
        axes[2].plot(t, s.series.tob_nm / 1e3, color=c, lw=0.8, label=f"{name}: on bit")
        axes[2].plot(t, s.series.surface_torque_nm / 1e3, color=c, lw=0.6, ls="--",
                     label=f"{name}: surface")
        if s.motor_torque_nm is not None:
            axes[3].plot(t, s.motor_torque_nm / 1e3, color=c, lw=0.8, label=name)
        if s.events.torque_limits_nm is not None:
            limits.update(s.events.torque_limits_nm)
        origin = round(s.series.time_s[0] * 1e9)
        for ns, kind, values in s.events.events:
            at = (ns - origin) / 1e9
            for a in axes:
                a.axvline(at, color=c, ls="-.", lw=0.8, alpha=0.8)
            label = kind + (f" {values['law']}" if kind == "controller" and "law" in values
                            else "")
            axes[0].annotate(label, (at, 1.0), xycoords=("data", "axes fraction"),
                             xytext=(3, -10 - 10 * (labels % 8)), textcoords="offset points",
                             fontsize=8, color=c)
            labels += 1
    for limit in sorted(limits):
        axes[3].axhline(limit / 1e3, color="tab:red", ls=":", lw=1.0)
    for a, label in zip(axes, ("speed [rpm]", "WOB [kN]", "torque [kN m]",
                               "motor torque [kN m]"), strict=True):
        a.set_ylabel(label)
        a.grid(alpha=0.3)
        if a.get_legend_handles_labels()[0]:
            a.legend(loc="upper right", fontsize=7)
    axes[0].set_title("drill_sim bag compare: " + " vs ".join(s.path.name for s in sessions))
    axes[-1].set_xlabel("time from each session's first sample [s]")
    fig.savefig(path, dpi=110)
    plt.close(fig)
