"""``drill_sim bag export``: the rig's time series as CSV, SI column names, streamed a chunk
at a time. ``time_s`` is seconds after the session's first sample, at full precision; then
the joint_states quantities; then, for each stamped topic the bag has beside them
(``bag.stamped_series``), its columns matched by stamp, empty where a sample has none:
``motor_torque_nm`` (the top drive's motor) and ``measured_*`` (what the rig's sensors showed,
e.g. ``measured_surface_torque_nm``); the last column, ``stamp_ns``, is each sample's header
stamp (nanoseconds, absolute)."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

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
            extra = [c for spec, _ in s.stamped for c in spec.columns]
            out.write(",".join((*COLUMNS[:-1], *extra, COLUMNS[-1])) + "\n")
            for ns, values in s.chunks:
                rows += ns.size
                beside = np.hstack([m.at(ns) for _, m in s.stamped]) if extra else None
                out.writelines(_lines(ns, values, s.chunks.origin_ns, beside))
        status = s.verdict(args)
        if status:
            return status
        tmp.replace(args.out)
    finally:
        tmp.unlink(missing_ok=True)
    print(f"{rows} rows written to {args.out}")
    return 0


def _lines(ns, values, origin_ns: int, beside: np.ndarray | None) -> list[str]:
    """CSV lines: every float at full precision (shortest repr that reads back exactly); a
    stamped topic's value missing at a sample is an empty field."""
    picked = values[:, [VALUE_COLUMN[name] for name in JOINT_FIELDS]].tolist()
    times = ((ns - origin_ns) / 1e9).tolist()
    extra = [""] * ns.size if beside is None else \
        ["".join("," + (repr(m) if m == m else "") for m in row) for row in beside.tolist()]
    return [f"{t!r},{','.join(map(repr, row))}{more},{stamp}\n"
            for t, row, more, stamp in zip(times, picked, extra, ns.tolist(), strict=True)]
