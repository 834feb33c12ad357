"""``drill_sim bag info``: a summary like ``ros2 bag info``, on any bag, even a damaged one;
exit status 1 when the bag is damaged (data lost)."""

from __future__ import annotations

import argparse
import datetime as dt
import json
from pathlib import Path

from ...bag.bag import Bag, BagInfo

HELP = "topics, types, counts, duration, metadata, damage (exit 1 if the bag is damaged)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("bag", type=Path, help="bag directory or .mcap file")
    parser.add_argument("--quick", action="store_true",
                        help="trust each file's summary without checking every chunk's CRC")


def run(args: argparse.Namespace) -> int:
    with Bag.open(args.bag) as bag:
        found = bag.info(verify=not args.quick)
        print(render(found))
    return 1 if found.problems else 0


def render(i: BagInfo) -> str:
    """A summary like ``ros2 bag info``."""
    start = "-" if i.start_ns is None else \
        dt.datetime.fromtimestamp(i.start_ns * 1e-9, dt.timezone.utc).isoformat()
    lines = [f"Files:             {', '.join(f.name for f in i.files)}",
             f"Duration:          {i.duration_s:.3f} s of log time (the wall clock while "
             "recording)",
             *_stamp_lines(i),
             f"Start:             {start}",
             f"Messages:          {i.message_count}"
             + (" (readable; more were lost: see Problems)" if i.problems else ""),
             *_loss_lines(i),
             "Topic information:"]
    width = max((len(t.name) for t in i.topics.values()), default=0)
    for t in i.topics.values():
        lines.append(f"  {t.name:<{width}}  {t.type_name:<36} {t.count:>10} msgs")
    for name, data in i.metadata.items():
        if name == "rosbag2":
            continue
        lines.append(f"Metadata '{name}':")
        lines += [f"  {k}: {v}" for k, v in data.items()]
    if i.notes:
        lines.append("Notes:")
        lines += [f"  {n}" for n in i.notes]
    if i.problems:
        lines.append("Problems (data lost; 'drill_sim bag repair' rewrites the bag from every "
                     "intact chunk, keeping the originals):")
        lines += [f"  {p}" for p in i.problems]
    return "\n".join(lines)


def _loss_lines(i: BagInfo) -> list[str]:
    """What the recorder never received (its ``recording`` record, ``bag.losses``)."""
    recording = i.metadata.get("recording", {})
    if "lost_messages" not in recording:
        return []
    lost = recording["lost_messages"]
    if lost == "0":
        return ["Lost in recording: none (counted from the publishers' sequence numbers)"]
    try:
        by_topic = ", ".join(f"{t} {n}" for t, n in json.loads(
            recording.get("lost_by_topic", "{}")).items())
    except ValueError:
        by_topic = "?"
    return [f"Lost in recording: {lost} messages never reached the recorder ({by_topic}; "
            "each gap under Metadata 'recording')"]


def _stamp_lines(i: BagInfo) -> list[str]:
    """The rig's own clock: the span of its joint_states header stamps, as simulated time
    for a sim-time session (whose stamps count from 0)."""
    session = i.metadata.get("session", {})
    epoch = session.get("stamp_epoch_ns")
    lines = []
    for topic, (first, last) in sorted(i.stamps.items()):
        if epoch == "0":
            lines.append(f"Simulated time:    {(last - first) * 1e-9:.3f} s ({first * 1e-9:.3f} "
                         f"to {last * 1e-9:.3f} s; header stamps of {topic}, a sim-time "
                         "session)")
        else:
            lines.append(f"Stamped span:      {(last - first) * 1e-9:.3f} s (header stamps of "
                         f"{topic}" + (", wall clock: a real-time session" if epoch else "")
                         + ")")
    return lines
