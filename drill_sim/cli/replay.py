"""``drill_sim_replay BAG``: publishes a bag's messages with their recorded timing.

Like ``ros2 bag play``: any rosbag2 MCAP bag (or bare ``.mcap``) whose message types are
installed here, each topic with the QoS its recorded publishers offered. Playback starts once
subscribers have matched, so none of the first messages is lost. ``--clock`` publishes
``/clock`` from the recorded times for nodes running with ``use_sim_time``. The player itself
is ``drill_sim.ros.replay``; this module is its command line.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import rclpy
from rclpy.utilities import remove_ros_args

from ..bag.bag import Bag, BagInfo
from ..bag.errors import BagError
from ..ros.replay import Player, PlayOptions
from ..ros.stopping import init_stoppable
from ..terminal import StatusLine
from .errors import UsageError

DESCRIPTION = "Publish a bag's messages with their recorded timing (what `ros2 bag play` does)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("bag", help="bag directory (rosbag2, MCAP storage) or .mcap file")
    parser.add_argument("-r", "--rate", type=float, default=1.0,
                        help="playback speed relative to the recording (default 1)")
    parser.add_argument("-l", "--loop", action="store_true", help="play again and again")
    parser.add_argument("--start-offset", type=float, default=0.0, metavar="S",
                        help="start S seconds into the bag")
    parser.add_argument("--topics", nargs="+", metavar="TOPIC", help="replay only these topics")
    parser.add_argument("--clock", type=float, nargs="?", const=100.0, default=0.0,
                        metavar="HZ", help="publish /clock from the recorded times at HZ "
                        "(default 100 when given)")
    parser.add_argument("--queue-depth", type=int, default=1000,
                        help="publisher history depth per topic [messages] (default 1000)")
    parser.add_argument("--wait-for", type=_count_or_all, default=1, metavar="N|all",
                        help="wait for at least N matched subscriptions before playing "
                             "(default 1; 0 = do not wait); all: for one on every topic")
    parser.add_argument("--wait-timeout", type=float, default=30.0, metavar="S",
                        help="play anyway after S seconds of waiting (default 30)")


def _check(args: argparse.Namespace) -> None:
    """What argparse cannot check alone, as UsageError."""
    checks = [("--rate", args.rate, args.rate > 0 and math.isfinite(args.rate), "> 0"),
              ("--start-offset", args.start_offset,
               args.start_offset >= 0 and math.isfinite(args.start_offset), ">= 0"),
              ("--clock", args.clock, args.clock >= 0 and math.isfinite(args.clock), "> 0 Hz"),
              ("--queue-depth", args.queue_depth, args.queue_depth >= 1, ">= 1"),
              ("--wait-for", args.wait_for, args.wait_for == "all" or args.wait_for >= 0,
               ">= 0 (or all)"),
              ("--wait-timeout", args.wait_timeout, args.wait_timeout >= 0, ">= 0 s")]
    for name, value, ok, expected in checks:
        if not ok:
            raise UsageError(f"{name} = {value}: expected a number {expected}")


def run(args: argparse.Namespace) -> int:
    """Play as ``args`` says; ``args.argv``, the whole command line with any ROS arguments
    (``main`` sets it; default ``sys.argv``), goes to rclpy."""
    _check(args)
    argv = getattr(args, "argv", None) or sys.argv
    bag = Path(args.bag)
    try:
        source = Bag.open(bag)                  # opened once: info, then every pass
        found = source.info()
    except BagError as exc:
        print(f"drill_sim_replay: {exc}", file=sys.stderr)
        return 2
    for problem in found.problems:
        print(f"drill_sim_replay: {problem}", file=sys.stderr)
    topics = {name: (t.type_name, t.offered_qos_profiles) for name, t in found.topics.items()
              if t.count and (args.topics is None or name in args.topics)}
    missing = sorted(set(args.topics or ()) - set(found.topics))
    if missing:
        print(f"drill_sim_replay: not in {bag}: {', '.join(missing)}; it has "
              f"{', '.join(sorted(found.topics)) or 'no topics'}", file=sys.stderr)
        return 2
    if not topics or found.start_ns is None:
        print(f"drill_sim_replay: {bag}: no message to replay", file=sys.stderr)
        return 2
    if args.start_offset > found.duration_s:
        print(f"drill_sim_replay: --start-offset = {args.start_offset:g} s is past the bag's "
              f"end ({found.duration_s:.3f} s)", file=sys.stderr)
        return 2
    try:
        return _play(args, argv, bag, source, found, topics)
    finally:
        source.close()


def _play(args: argparse.Namespace, argv: list[str], bag: Path, source: Bag, found: BagInfo,
          topics: dict[str, tuple[str, str]]) -> int:
    stop = init_stoppable(argv)
    player = Player(source, topics, found.start_ns, PlayOptions(
        rate=args.rate, start_offset_s=args.start_offset, clock_hz=args.clock,
        queue_depth=args.queue_depth, wait_for=1 if args.wait_for == "all" else args.wait_for,
        wait_for_every_topic=args.wait_for == "all", wait_timeout_s=args.wait_timeout))
    try:
        if not player.publishers_by_topic:
            print("drill_sim_replay: none of the bag's message types is installed here",
                  file=sys.stderr)
            return 2
        names = ", ".join(sorted(player.publishers_by_topic))
        print(f"drill_sim_replay: {bag}: {len(player.publishers_by_topic)} topics ({names}), "
              f"{found.duration_s:.3f} s at {args.rate:g}x", file=sys.stderr)
        missing = player.wait_for_subscribers(stop) if args.wait_for else None
        if stop:
            return 0
        if missing:
            print(f"drill_sim_replay: {missing}; playing anyway", file=sys.stderr)
        progress = _Progress(found.start_ns, found.end_ns)
        while not stop:
            player.play_once(stop, progress)
            if not args.loop:
                break
        progress.close()
        player.wait_acked(10.0)
        print(f"drill_sim_replay: published {player.sent} messages", file=sys.stderr)
    finally:
        player.destroy_node()
        rclpy.try_shutdown()
    return 0


def _count_or_all(text: str) -> int | str:
    if text == "all":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a whole number or all") from None


def main(argv: list[str] | None = None) -> int:
    """The ``drill_sim_replay`` console script: ROS arguments are left to rclpy."""
    argv = sys.argv if argv is None else argv
    parser = argparse.ArgumentParser(prog="drill_sim_replay", description=DESCRIPTION)
    add_arguments(parser)
    parser.set_defaults(argv=argv)
    args = parser.parse_args(remove_ros_args(argv)[1:])
    try:
        return run(args)
    except UsageError as exc:
        parser.error(str(exc))      # usage and the message on stderr, status 2, as argparse does


class _Progress:
    """Bag time on a terminal line, ten times a second."""

    def __init__(self, start_ns: int, end_ns: int) -> None:
        self.start, self.span = start_ns, max(end_ns - start_ns, 1)
        self.line = StatusLine(0.1)

    def __call__(self, log_ns: int) -> None:
        if self.line.due():
            self.line.show(f"replaying: {(log_ns - self.start) * 1e-9:9.3f} s of "
                           f"{self.span * 1e-9:.3f} s "
                           f"({100 * (log_ns - self.start) / self.span:5.1f} %)")

    def close(self) -> None:
        self.line.close()


if __name__ == "__main__":
    sys.exit(main())
