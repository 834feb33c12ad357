"""``drill_sim bag export``: the rig's time series as CSV, SI column names, streamed a chunk
at a time. ``time_s`` is seconds after the session's first sample, at full precision; then
the joint_states quantities, ``motor_torque_nm`` when the bag has the top drive's motor torque
(matched by stamp; empty where a sample has none); the last column, ``stamp_ns``, is each
sample's header stamp (nanoseconds, absolute)."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ...bag.motor_series import COLUMN as MOTOR_COLUMN
from ...bag.series import JOINT_FIELDS, VALUE_COLUMN
from . import window

HELP = "the rig's time series as CSV (SI columns; time_s after the first sample, stamp_ns)"
COLUMNS = ("time_s", *JOINT_FIELDS, "stamp_ns")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    window.add_arguments(parser)
    parser.add_argument("--out", type=Path, required=True, help="output file")


def run(args: argparse.Namespace) -> int:
    window.check(args, args.out)
    tmp = args.out.with_name(args.out.name + ".tmp")
    rows = 0
    try:
        with window.samples(args) as s, open(tmp, "w", encoding="ascii") as out:
            columns = COLUMNS if s.motor is None else (*COLUMNS[:-1], MOTOR_COLUMN, COLUMNS[-1])
            out.write(",".join(columns) + "\n")
            for ns, values in s.chunks:
                rows += ns.size
                motor = None if s.motor is None else s.motor.at(ns)
                out.writelines(_lines(ns, values, s.chunks.origin_ns, motor))
        status = s.verdict(args)
        if status:
            return status
        tmp.replace(args.out)
    finally:
        tmp.unlink(missing_ok=True)
    print(f"{rows} rows written to {args.out}")
    return 0


def _lines(ns, values, origin_ns: int, motor: np.ndarray | None) -> list[str]:
    """CSV lines: every float at full precision (shortest repr that reads back exactly)."""
    picked = values[:, [VALUE_COLUMN[name] for name in JOINT_FIELDS]].tolist()
    times = ((ns - origin_ns) / 1e9).tolist()
    extra = [""] * ns.size if motor is None else \
        ["," + (repr(m) if m == m else "") for m in motor.tolist()]
    return [f"{t!r},{','.join(map(repr, row))}{more},{stamp}\n"
            for t, row, more, stamp in zip(times, picked, extra, ns.tolist(), strict=True)]
