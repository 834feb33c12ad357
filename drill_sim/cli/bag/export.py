"""``drill_sim bag export``: the rig's time series as CSV, SI column names, streamed a chunk
at a time. ``time_s`` is seconds after the session's first sample, at full precision; the
last column, ``stamp_ns``, is each sample's header stamp (nanoseconds, absolute)."""

from __future__ import annotations

import argparse
from pathlib import Path

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
            out.write(",".join(COLUMNS) + "\n")
            for ns, values in s.chunks:
                rows += ns.size
                out.writelines(_lines(ns, values, s.chunks.origin_ns))
        status = s.verdict(args)
        if status:
            return status
        tmp.replace(args.out)
    finally:
        tmp.unlink(missing_ok=True)
    print(f"{rows} rows written to {args.out}")
    return 0


def _lines(ns, values, origin_ns: int) -> list[str]:
    """CSV lines: every float at full precision (shortest repr that reads back exactly)."""
    picked = values[:, [VALUE_COLUMN[name] for name in JOINT_FIELDS]].tolist()
    times = ((ns - origin_ns) / 1e9).tolist()
    return [f"{t!r},{','.join(map(repr, row))},{stamp}\n"
            for t, row, stamp in zip(times, picked, ns.tolist(), strict=True)]
