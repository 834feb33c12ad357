"""``drill_sim bag export``: the rig's time series as CSV, SI column names."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from . import window

HELP = "the rig's time series as CSV (SI columns)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    window.add_arguments(parser)
    parser.add_argument("--out", type=Path, required=True, help="output file")


def run(args: argparse.Namespace) -> int:
    window.check(args, args.out)
    s = window.series(args)
    fields = [f for f in s.__dataclass_fields__ if f != "topic"]
    np.savetxt(args.out, np.column_stack([getattr(s, f) for f in fields]), delimiter=",",
               header=",".join(fields), comments="", fmt="%.9g")
    print(f"{s.time_s.size} rows written to {args.out}")
    return 0
