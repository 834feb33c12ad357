"""``drill_sim bag``: tools on rosbag2 MCAP bags (any bag, not only the ones drill_sim wrote)."""

from __future__ import annotations

import argparse
import datetime as dt
import json
import math
from pathlib import Path

import numpy as np

from ..bag import reader
from ..bag.resim import resimulate
from ..bag.series import rig_series
from ..bag.writer import BagError
from ..wire import WireError
from .errors import UsageError
from .plot import plot_rig_series
from .progress import Progress


def add_arguments(sub) -> None:
    bag = sub.add_parser("bag", help="tools on rosbag2 MCAP bags: info, repair, metrics, "
                                     "export, plot, resim")
    tools = bag.add_subparsers(dest="bag_command", required=True, parser_class=type(bag))
    info = tools.add_parser("info", help="topics, types, counts, duration, metadata")
    info.add_argument("bag", type=Path, help="bag directory or .mcap file")
    repair = tools.add_parser("repair", help="rewrite a bag cut short by a crash: summary, "
                                             "indexes, metadata.yaml (originals kept)")
    repair.add_argument("bag", type=Path, help="bag directory")
    resim = tools.add_parser("resim", help="run the model again from the recorded parameters "
                             "and commands and compare with the recorded outputs (exit 1 if "
                             "they differ)")
    resim.add_argument("bag", type=Path, help="bag directory or .mcap file of a rig session")
    resim.add_argument("--json", action="store_true", help="one JSON object on stdout")
    for name, text in (("metrics", "SSI, stick fraction and means of a recorded rig session"),
                       ("export", "the rig's time series as CSV (SI columns)"),
                       ("plot", "PNG of bit speed, WOB, torques and the stick-slip flag")):
        tool = tools.add_parser(name, help=text)
        tool.add_argument("bag", type=Path, help="bag directory or .mcap file")
        tool.add_argument("--topic", help="the rig's joint_states topic, if the bag has several")
        tool.add_argument("--start", type=float, help="window start [s] after the first sample")
        tool.add_argument("--end", type=float, help="window end [s] after the first sample")
        if name == "metrics":
            tool.add_argument("--json", action="store_true", help="one JSON object on stdout")
        else:
            tool.add_argument("--out", type=Path, required=True, help="output file")


def run(args: argparse.Namespace) -> int:
    try:
        if args.bag_command == "info":
            print(render(reader.info(args.bag)))
        elif args.bag_command in ("metrics", "export", "plot"):
            return _series_command(args)
        elif args.bag_command == "resim":
            return _resim_command(args)
        else:
            result = reader.repair(args.bag)
            print(f"repaired {args.bag}: {result.message_count} messages over "
                  f"{result.duration_s:.3f} s kept; damaged originals left as *.mcap.damaged")
    except (BagError, WireError) as exc:
        raise UsageError(str(exc)) from None
    return 0


def _series_command(args: argparse.Namespace) -> int:
    for name in ("start", "end"):
        value = getattr(args, name)
        if value is not None and not (math.isfinite(value) and value >= 0):
            raise UsageError(f"--{name} = {value}: expected a time >= 0 s")
    out = getattr(args, "out", None)
    if out is not None and not out.parent.exists():
        raise UsageError(f"cannot write {out}: folder {out.parent} does not exist")
    s = rig_series(args.bag, args.topic).window(args.start, args.end)
    if args.bag_command == "metrics":
        m = s.metrics()
        if args.json:
            print(json.dumps(m))
        else:
            print(f"{s.topic}: {m['samples']} samples over {m['duration_s']:.3f} s")
            for key, value in m.items():
                if key not in ("samples", "duration_s"):
                    print(f"  {key:<24} {value:.6g}")
    elif args.bag_command == "export":
        fields = [f for f in s.__dataclass_fields__ if f != "topic"]
        np.savetxt(out, np.column_stack([getattr(s, f) for f in fields]), delimiter=",",
                   header=",".join(fields), comments="", fmt="%.9g")
        print(f"{s.time_s.size} rows written to {out}")
    else:
        plot_rig_series(out, s, title=f"{args.bag.name}: {s.topic}")
        print(f"plot written to {out}")
    return 0


def _resim_command(args: argparse.Namespace) -> int:
    progress = Progress("re-simulating")
    try:
        r = resimulate(args.bag, progress)
    finally:
        progress.close()
    if args.json:
        print(json.dumps({"bag": str(r.bag), "mode": r.mode, "preset": r.preset,
                          "samples": r.samples, "commands": r.commands, "refused": r.refused,
                          "events": r.events, "exact": r.exact,
                          "max_difference": r.max_difference,
                          "worst": dict(zip(("quantity", "difference", "time_s"), r.worst,
                                            strict=True)),
                          "explanation": r.explanation()}))
        return 0 if r.exact else 1
    print(f"{r.bag}: {r.mode} session (preset {r.preset}), {r.samples} samples, "
          f"{r.commands} commands used, {r.refused} refused, "
          f"{r.events.count('reset')} resets, {r.events.count('parameters')} parameter changes")
    print("largest difference re-run - recorded, per quantity:")
    for name, value in r.max_difference.items():
        print(f"  {name:<24} {value:.3g}")
    if not r.exact:
        name, value, t = r.worst
        print(f"worst: {name} off by {value:.3g} at t = {t:.6f} s")
    print(r.explanation())
    return 0 if r.exact else 1


def render(i: reader.BagInfo) -> str:
    """A summary like ``ros2 bag info``."""
    start = "-" if i.start_ns is None else \
        dt.datetime.fromtimestamp(i.start_ns * 1e-9, dt.timezone.utc).isoformat()
    lines = [f"Files:             {', '.join(f.name for f in i.files)}",
             f"Duration:          {i.duration_s:.3f} s",
             f"Start:             {start}",
             f"Messages:          {i.message_count}",
             "Topic information:"]
    width = max((len(t.name) for t in i.topics.values()), default=0)
    for t in i.topics.values():
        lines.append(f"  {t.name:<{width}}  {t.type_name:<36} {t.count:>10} msgs")
    for name, data in i.metadata.items():
        if name == "rosbag2":
            continue
        lines.append(f"Metadata '{name}':")
        lines += [f"  {k}: {v}" for k, v in data.items()]
    if i.problems:
        lines.append("Problems (run 'drill_sim bag repair' on a bag cut short):")
        lines += [f"  {p}" for p in i.problems]
    return "\n".join(lines)
