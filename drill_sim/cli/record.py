"""``drill_sim_record``: records topics of the ROS graph into a rosbag2 MCAP bag.

Like ``ros2 bag record``: the listed topics, a regular expression, or all; topics that appear
later are picked up as they are discovered. Ctrl-C or SIGTERM closes the bag properly; a killed
recorder loses at most the last second, and ``drill_sim bag repair`` restores the rest. The
recorder itself is ``drill_sim.ros.record``; this module is its command line.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from datetime import datetime
from pathlib import Path

from rclpy.utilities import remove_ros_args

from .. import __version__
from ..bag.writer import BagError, BagWriter
from ..ros.record import TopicSelection, record
from ..ros.stopping import init_stoppable
from .errors import UsageError

DESCRIPTION = "Record topics into a rosbag2 MCAP bag (what `ros2 bag record` does)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("topics", nargs="*", help="topic names to record")
    parser.add_argument("-a", "--all", action="store_true", help="record every topic")
    parser.add_argument("-e", "--regex", help="record topics matching this regular expression")
    parser.add_argument("-x", "--exclude", help="skip topics matching this regular expression")
    parser.add_argument("-o", "--output", help="bag directory to create "
                        "(default: drill_sim_record_<date>-<time>)")
    parser.add_argument("-d", "--max-bag-duration", type=float, default=0.0, metavar="S",
                        help="start a new file every S seconds (0 = never)")
    parser.add_argument("-b", "--max-bag-size", type=int, default=0, metavar="BYTES",
                        help="start a new file past this size (0 = never)")
    parser.add_argument("--duration", type=float, default=0.0, metavar="S",
                        help="stop after S seconds of wall time (0 = until Ctrl-C)")
    parser.add_argument("--queue-depth", type=int, default=1000,
                        help="subscription history depth per topic [messages] (default 1000)")
    parser.add_argument("--discovery-period", type=float, default=0.1, metavar="S",
                        help="how often to look for new topics [s] (default 0.1)")


def _check(args: argparse.Namespace) -> None:
    """What argparse cannot check alone, as UsageError."""
    if not (args.topics or args.all or args.regex):
        raise UsageError("name topics, or give --regex or --all")
    for name, value in (("--max-bag-duration", args.max_bag_duration),
                        ("--max-bag-size", args.max_bag_size), ("--duration", args.duration)):
        if not value >= 0:
            raise UsageError(f"{name} = {value}: expected a number >= 0")
    if not (args.queue_depth >= 1 and args.discovery_period > 0):
        raise UsageError("--queue-depth must be >= 1 and --discovery-period > 0")
    if args.regex or args.exclude:
        try:
            re.compile(args.regex or ""), re.compile(args.exclude or "")
        except re.error as exc:
            raise UsageError(f"bad regular expression: {exc}") from None


def run(args: argparse.Namespace) -> int:
    """Record as ``args`` says; ``args.argv``, the whole command line with any ROS arguments
    (``main`` sets it; default ``sys.argv``), goes to rclpy and into the bag's metadata."""
    _check(args)
    argv = getattr(args, "argv", None) or sys.argv
    output = Path(args.output or datetime.now().strftime("drill_sim_record_%Y_%m_%d-%H_%M_%S"))
    session = {"package": "drill_sim", "version": __version__,
               "start_time_ns": str(time.time_ns()), "command_line": json.dumps(argv)}
    try:
        writer = BagWriter(output, split_duration_s=args.max_bag_duration,
                           split_size_bytes=args.max_bag_size, metadata={"session": session})
    except BagError as exc:
        print(f"drill_sim_record: {exc}", file=sys.stderr)
        return 2
    stop = init_stoppable(argv)
    error = record(writer, TopicSelection(args.topics, args.regex, args.all, args.exclude), stop,
                   queue_depth=args.queue_depth, duration_s=args.duration,
                   discovery_period_s=args.discovery_period)
    counts = ", ".join(f"{t.name} {t.count}" for t in writer.topics.values()) or "no topics"
    print(f"drill_sim_record: {sum(t.count for t in writer.topics.values())} messages in "
          f"{output} ({counts})", file=sys.stderr)
    if error is not None:
        print(f"drill_sim_record: {error}", file=sys.stderr)
        return 1
    return 0


def main(argv: list[str] | None = None) -> int:
    """The ``drill_sim_record`` console script: ROS arguments are left to rclpy."""
    argv = sys.argv if argv is None else argv
    parser = argparse.ArgumentParser(prog="drill_sim_record", description=DESCRIPTION)
    add_arguments(parser)
    parser.set_defaults(argv=argv)
    args = parser.parse_args(remove_ros_args(argv)[1:])
    try:
        return run(args)
    except UsageError as exc:
        parser.error(str(exc))      # usage and the message on stderr, status 2, as argparse does


if __name__ == "__main__":
    sys.exit(main())
