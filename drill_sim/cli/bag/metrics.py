"""``drill_sim bag metrics``: SSI, stick fraction and means of a recorded rig session, and the
drive's effort and settling (``core.effort``), summed a chunk at a time (memory does not grow
with the bag)."""

from __future__ import annotations

import argparse
import json

import numpy as np

from ...bag.errors import BagError
from ...bag.rig_stats import RigStats
from ...bag.series import columns
from ...bag.session_events import session_events
from ...core.effort import EffortStats
from . import window

HELP = "SSI, stick fraction and means of a recorded rig session (default: all of it)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    window.add_arguments(parser)
    parser.add_argument("--json", action="store_true", help="one JSON object on stdout")


def run(args: argparse.Namespace) -> int:
    window.check(args)
    motor_sum_nm, motor_n = 0.0, 0
    with window.samples(args) as s:
        stats = RigStats(s.topic)
        facts = session_events(s.bag)
        effort = None
        for ns, values in s.chunks:
            t = (ns - s.chunks.origin_ns) / 1e9
            named = columns(values)
            stats.add(t, named)
            if effort is None:
                effort = EffortStats(facts.torque_limits_nm, [
                    (at - s.chunks.origin_ns) / 1e9 for at in facts.switches_ns])
            motor = None
            if s.motor is not None:
                motor = s.motor.at(ns)[:, 0]
                finite = motor[np.isfinite(motor)]
                motor_sum_nm, motor_n = motor_sum_nm + float(finite.sum()), motor_n + finite.size
            effort.add(t, named["bit_speed_rad_s"], motor, named["top_drive_speed_rad_s"])
    status = s.verdict(args, stats.problems())
    if status:
        return status
    if stats.n == 0:
        raise BagError(f"{s.topic}: no samples in the window; {s.chunks.span()}")
    m = stats.result()
    if motor_n:                        # the top drive's motor, when the bag has its torque
        m["mean_motor_torque_nm"] = motor_sum_nm / motor_n
    m.update((effort or EffortStats()).result())
    problems = list(dict.fromkeys(s.problems + stats.problems()))
    if args.json:
        print(json.dumps({**m, "problems": problems}))
        return 0
    print(f"{s.topic}: {m['samples']} samples over {m['duration_s']:.3f} s of header stamps"
          + (" (partial: the bag is damaged)" if problems else ""))
    for key, value in m.items():
        if key not in ("samples", "duration_s"):
            print(f"  {key:<29} {'-' if value is None else format(value, '.6g')}")
    return 0
