"""What ``metrics``, ``export`` and ``plot`` share: the rig's series from a bag, cut to a
time window."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ...bag.bag import Bag
from ...bag.series import RigSeries, rig_series
from ..errors import UsageError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("bag", type=Path, help="bag directory or .mcap file")
    parser.add_argument("--topic", help="the rig's joint_states topic, if the bag has several")
    parser.add_argument("--start", type=float, help="window start [s] after the first sample")
    parser.add_argument("--end", type=float, help="window end [s] after the first sample")


def check(args: argparse.Namespace, out: Path | None = None) -> None:
    """Refuse a bad window or an output in a missing folder before reading anything."""
    for name in ("start", "end"):
        value = getattr(args, name)
        if value is not None and not (math.isfinite(value) and value >= 0):
            raise UsageError(f"--{name} = {value}: expected a time >= 0 s")
    if out is not None and not out.parent.exists():
        raise UsageError(f"cannot write {out}: folder {out.parent} does not exist")


def series(args: argparse.Namespace) -> RigSeries:
    with Bag.open(args.bag) as bag:
        return rig_series(bag, args.topic).window(args.start, args.end)
