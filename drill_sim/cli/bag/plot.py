"""``drill_sim bag plot``: PNG of the rig's session against time."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ...bag.series import RigSeries
from ...bag.session_events import SessionEvents, session_events
from ..plot import plot_rig_series
from . import window

HELP = ("PNG of bit and top-drive speed, WOB, torques (motor too, against the drive's limits, "
        "when recorded), stuck phases, the recorded events")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    window.add_arguments(parser)
    parser.add_argument("--out", type=Path, required=True, help="output file")


def event_marks(facts: SessionEvents, series: RigSeries) -> dict[float, str]:
    """The session's recorded events (controller switch, parameter changes, reset, formation)
    as plot marks: seconds after the series' first sample -> label."""
    origin = round(series.time_s[0] * 1e9) if series.time_s.size else 0
    end = series.time_s[-1] - series.time_s[0] if series.time_s.size else 0.0
    marks: dict[float, str] = {}
    for ns, kind, values in facts.events:
        at = (ns - origin) / 1e9
        if 0.0 <= at <= end:
            label = kind + (f" {values['law']}" if "law" in values else "")
            near = next((m for m in marks if abs(m - at) < 0.01 * max(end, 1.0)), None)
            if near is None:
                marks[at] = label
            else:                            # one mark for events that would overlap
                marks[near] = f"{marks[near]}, {label}"
    return marks


def run(args: argparse.Namespace) -> int:
    window.check(args, args.out)
    with window.samples(args) as s:
        chunks = list(s.chunks)
        facts = session_events(s.bag)
        series = RigSeries.from_chunks(s.topic, chunks)
        motor = None if s.motor is None else \
            np.concatenate([s.motor.at(ns)[:, 0] for ns, _ in chunks])
    status = s.verdict(args)
    if status:
        return status
    plot_rig_series(args.out, series, title=f"{args.bag.name}: {s.topic}",
                    motor_torque_nm=motor, marks=event_marks(facts, series),
                    torque_limits_nm=None if motor is None else facts.torque_limits_nm)
    print(f"plot written to {args.out}")
    return 0
