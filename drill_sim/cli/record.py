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

from .. import __version__
from ..bag.writer import BagError, BagWriter
from ..ros.record import TopicSelection, record
from ..ros.stopping import init_stoppable, without_ros_args
from .checks import in_range, integer, join_negative_values, new_bag, number, whole
from .errors import Parser, UsageError

DESCRIPTION = "Record topics into a rosbag2 MCAP bag (what `ros2 bag record` does)."


# The documented limits (msg_docs/cli.md, "Limits").
MAX_SECONDS = 1e7              # --duration and --max-bag-duration [s], about 116 days
MAX_BAG_SIZE = 1 << 40         # --max-bag-size [bytes], 1 TiB
MAX_QUEUE_DEPTH = 100_000      # messages per topic
DISCOVERY_RANGE = (0.01, 60.0)  # [s]
MAX_GAP_LINES = 20             # gaps printed at the end; the bag keeps them all


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("topics", nargs="*", help="topic names to record")
    parser.add_argument("-a", "--all", action="store_true", help="record every topic")
    parser.add_argument("-e", "--regex", help="record topics matching this regular expression")
    parser.add_argument("-x", "--exclude", help="skip topics matching this regular expression")
    parser.add_argument("-o", "--output", type=Path,
                        help="bag directory to create, in an existing folder "
                             "(default: drill_sim_record_<date>-<time>)")
    parser.add_argument("-d", "--max-bag-duration", type=number, default=0.0, metavar="S",
                        help=f"start a new file every S seconds (0 = never), up to "
                             f"{MAX_SECONDS:g}")
    parser.add_argument("-b", "--max-bag-size", type=integer, default=0, metavar="BYTES",
                        help=f"start a new file past this size (0 = never), up to {MAX_BAG_SIZE}")
    parser.add_argument("--duration", type=number, default=0.0, metavar="S",
                        help=f"stop after S seconds of wall time (0 = until Ctrl-C), up to "
                             f"{MAX_SECONDS:g}")
    parser.add_argument("--queue-depth", type=integer, default=0,
                        help="subscription history depth per topic [messages], 1 to "
                             f"{MAX_QUEUE_DEPTH}; 0 (default): keep all (nothing dropped while "
                             "the recorder falls behind; memory grows meanwhile)")
    parser.add_argument("--discovery-period", type=number, default=0.1, metavar="S",
                        help="how often to look for new topics [s], "
                             f"{DISCOVERY_RANGE[0]:g} to {DISCOVERY_RANGE[1]:g} (default 0.1)")


def _check(args: argparse.Namespace) -> None:
    """What argparse cannot check alone, as UsageError."""
    if not (args.topics or args.all or args.regex):
        raise UsageError("name topics, or give --regex or --all")
    in_range("-d/--max-bag-duration", args.max_bag_duration, 0.0, MAX_SECONDS, unit="s",
             what="a file length")
    whole("-b/--max-bag-size", args.max_bag_size, 0, MAX_BAG_SIZE, unit="bytes",
          what="a file size:")
    in_range("--duration", args.duration, 0.0, MAX_SECONDS, unit="s", what="a recording time")
    whole("--queue-depth", args.queue_depth, 0, MAX_QUEUE_DEPTH, unit="messages",
          what="a history depth:")
    in_range("--discovery-period", args.discovery_period, *DISCOVERY_RANGE, unit="s",
             what="a period")
    if args.regex or args.exclude:
        try:
            re.compile(args.regex or ""), re.compile(args.exclude or "")
        except re.error as exc:
            raise UsageError(f"bad regular expression: {exc}") from None
    if args.output is not None:
        new_bag("-o/--output", args.output)


def run(args: argparse.Namespace) -> int:
    """Record as ``args`` says; ``args.argv``, the whole command line with any ROS arguments
    (``main`` sets it; default ``sys.argv``), goes to rclpy and into the bag's metadata."""
    _check(args)
    argv = getattr(args, "argv", None) or sys.argv
    output = args.output or Path(datetime.now().strftime("drill_sim_record_%Y_%m_%d-%H_%M_%S"))
    session = {"package": "drill_sim", "version": __version__,
               "start_time_ns": str(time.time_ns()), "command_line": json.dumps(argv)}
    try:
        writer = BagWriter(output, split_duration_s=args.max_bag_duration,
                           split_size_bytes=args.max_bag_size, metadata={"session": session})
    except BagError as exc:
        print(f"drill_sim_record: {exc}", file=sys.stderr)
        return 2
    stop = init_stoppable(argv)
    error, gaps = record(writer, TopicSelection(args.topics, args.regex, args.all,
                                                args.exclude), stop,
                         queue_depth=args.queue_depth, duration_s=args.duration,
                         discovery_period_s=args.discovery_period)
    counts = ", ".join(f"{t.name} {t.count}" for t in writer.topics.values()) or "no topics"
    print(f"drill_sim_record: {sum(t.count for t in writer.topics.values())} messages in "
          f"{output} ({counts})", file=sys.stderr)
    for gap in gaps.gaps[:MAX_GAP_LINES]:
        print(f"drill_sim_record: {gap.line()}", file=sys.stderr)
    if len(gaps.gaps) > MAX_GAP_LINES:
        print(f"drill_sim_record: ... and {len(gaps.gaps) - MAX_GAP_LINES} more gaps (all in "
              "the bag's 'recording' metadata: drill_sim bag info)", file=sys.stderr)
    if gaps.lost:
        by_topic = ", ".join(f"{t} {n}" for t, n in gaps.lost_by_topic().items())
        print(f"drill_sim_record: LOST {gaps.lost} messages in all, counted from the "
              f"publishers' sequence numbers ({by_topic})", file=sys.stderr)
    else:
        print("drill_sim_record: none lost (counted from the publishers' sequence numbers"
              + (f"; not countable on {', '.join(sorted(gaps.uncounted))}: several publishers"
                 if gaps.uncounted else "") + ")", file=sys.stderr)
    if error is not None:
        print(f"drill_sim_record: {error}", file=sys.stderr)
        return 1
    return 0


def main(argv: list[str] | None = None) -> int:
    """The ``drill_sim_record`` console script: ROS arguments are left to rclpy."""
    argv = sys.argv if argv is None else argv
    parser = Parser(prog="drill_sim_record", description=DESCRIPTION)
    add_arguments(parser)
    parser.set_defaults(argv=argv)
    try:
        return run(parser.parse_args(join_negative_values(without_ros_args(argv)[1:])))
    except UsageError as exc:
        print(f"drill_sim_record: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
