"""``drill_sim bag``: tools on rosbag2 MCAP bags (any bag, not only the ones drill_sim wrote)."""

from __future__ import annotations

import argparse
import datetime as dt
from pathlib import Path

from ..bag import reader
from ..bag.writer import BagError
from .errors import UsageError


def add_arguments(sub) -> None:
    bag = sub.add_parser("bag", help="tools on rosbag2 MCAP bags: info, repair")
    tools = bag.add_subparsers(dest="bag_command", required=True, parser_class=type(bag))
    info = tools.add_parser("info", help="topics, types, counts, duration, metadata")
    info.add_argument("bag", type=Path, help="bag directory or .mcap file")
    repair = tools.add_parser("repair", help="rewrite a bag cut short by a crash: summary, "
                                             "indexes, metadata.yaml (originals kept)")
    repair.add_argument("bag", type=Path, help="bag directory")


def run(args: argparse.Namespace) -> int:
    try:
        if args.bag_command == "info":
            print(render(reader.info(args.bag)))
        else:
            result = reader.repair(args.bag)
            print(f"repaired {args.bag}: {result.message_count} messages over "
                  f"{result.duration_s:.3f} s kept; damaged originals left as *.mcap.damaged")
    except BagError as exc:
        raise UsageError(str(exc)) from None
    return 0


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
