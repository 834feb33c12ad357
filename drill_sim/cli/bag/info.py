"""``drill_sim bag info``: a summary like ``ros2 bag info``, on any bag, even a crashed one."""

from __future__ import annotations

import argparse
import datetime as dt
from pathlib import Path

from ...bag.bag import Bag, BagInfo

HELP = "topics, types, counts, duration, metadata"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("bag", type=Path, help="bag directory or .mcap file")


def run(args: argparse.Namespace) -> int:
    with Bag.open(args.bag) as bag:
        print(render(bag.info()))
    return 0


def render(i: BagInfo) -> str:
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
