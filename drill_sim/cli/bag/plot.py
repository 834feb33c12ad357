"""``drill_sim bag plot``: PNG of the rig's session against time."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ...bag.series import RigSeries
from ..plot import plot_rig_series
from . import window

HELP = "PNG of bit and top-drive speed, WOB, torques (motor too, when recorded), stuck phases"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    window.add_arguments(parser)
    parser.add_argument("--out", type=Path, required=True, help="output file")


def run(args: argparse.Namespace) -> int:
    window.check(args, args.out)
    with window.samples(args) as s:
        chunks = list(s.chunks)
        series = RigSeries.from_chunks(s.topic, chunks)
        motor = None if s.motor is None else \
            np.concatenate([s.motor.at(ns)[:, 0] for ns, _ in chunks])
    status = s.verdict(args)
    if status:
        return status
    plot_rig_series(args.out, series, title=f"{args.bag.name}: {s.topic}",
                    motor_torque_nm=motor)
    print(f"plot written to {args.out}")
    return 0
