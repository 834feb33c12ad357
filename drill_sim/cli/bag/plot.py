"""``drill_sim bag plot``: PNG of the rig's session against time."""

from __future__ import annotations

import argparse
from pathlib import Path

from ...bag.series import RigSeries
from ..plot import plot_rig_series
from . import window

HELP = "PNG of bit speed, WOB, torques and the stick-slip flag"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    window.add_arguments(parser)
    parser.add_argument("--out", type=Path, required=True, help="output file")


def run(args: argparse.Namespace) -> int:
    window.check(args, args.out)
    with window.samples(args) as s:
        series = RigSeries.from_chunks(s.topic, list(s.chunks))
    status = s.verdict(args)
    if status:
        return status
    plot_rig_series(args.out, series, title=f"{args.bag.name}: {s.topic}")
    print(f"plot written to {args.out}")
    return 0
