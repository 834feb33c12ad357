"""``drill_sim_replay BAG``: publishes a bag's messages with their recorded timing.

Like ``ros2 bag play``: any rosbag2 MCAP bag (or bare ``.mcap``) whose message types are
installed here, each topic with the QoS its recorded publishers offered. Playback starts once
subscribers have matched, so none of the first messages is lost. ``--clock`` publishes
``/clock`` from the recorded times for nodes running with ``use_sim_time``. The player itself
is ``drill_sim.ros.replay``; this module is its command line.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..bag.bag import Bag, BagInfo
from ..bag.errors import BagError
from ..ros.replay import Player, PlayOptions
from ..ros.stopping import init_stoppable, shutdown, without_ros_args
from ..terminal import StatusLine
from .checks import in_range, integer, join_negative_values, number, whole
from .errors import Parser, UsageError

DESCRIPTION = "Publish a bag's messages with their recorded timing (what `ros2 bag play` does)."


# The documented limits (msg_docs/cli.md, "Limits").
RATE_RANGE = (0.001, 1000.0)   # playback speed relative to the recording
MAX_OFFSET_S = 1e7             # --start-offset [s]
MAX_CLOCK_HZ = 10_000.0
MAX_QUEUE_DEPTH = 100_000      # messages per topic
MAX_WAIT_FOR = 1000            # subscriptions
MAX_WAIT_S = 86_400.0          # --wait-timeout [s], a day


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("bag", help="bag directory (rosbag2, MCAP storage) or .mcap file")
    parser.add_argument("-r", "--rate", type=number, default=1.0,
                        help="playback speed relative to the recording, "
                             f"{RATE_RANGE[0]:g} to {RATE_RANGE[1]:g} (default 1)")
    parser.add_argument("-l", "--loop", action="store_true", help="play again and again")
    parser.add_argument("--start-offset", type=number, default=0.0, metavar="S",
                        help="start S seconds into the bag")
    parser.add_argument("--topics", nargs="+", metavar="TOPIC", help="replay only these topics")
    parser.add_argument("--clock", type=number, nargs="?", const=100.0, default=0.0,
                        metavar="HZ", help="publish /clock from the recorded times at HZ, up to "
                        f"{MAX_CLOCK_HZ:g} (default 100 when given)")
    parser.add_argument("--queue-depth", type=integer, default=0,
                        help="publisher history depth per topic [messages], 1 to "
                             f"{MAX_QUEUE_DEPTH}; 0 (default): keep all, so that a reliable "
                             "subscriber that falls behind holds the replay back instead of "
                             "losing messages")
    parser.add_argument("--wait-for", type=_count_or_all, default=1, metavar="N|all",
                        help="wait for at least N matched subscriptions before playing "
                             f"(default 1; 0 = do not wait; up to {MAX_WAIT_FOR}); all: for one "
                             "on every topic")
    parser.add_argument("--wait-timeout", type=number, default=30.0, metavar="S",
                        help="play anyway after S seconds of waiting (default 30), up to "
                             f"{MAX_WAIT_S:g}")
    parser.add_argument("--partial", action="store_true",
                        help="replay the readable part of a damaged bag (without it a damaged "
                             "bag is refused with exit status 1)")


def _check(args: argparse.Namespace) -> None:
    """What argparse cannot check alone, as UsageError."""
    in_range("-r/--rate", args.rate, *RATE_RANGE, what="a playback speed",
             note="times the recorded speed")
    in_range("--start-offset", args.start_offset, 0.0, MAX_OFFSET_S, unit="s",
             what="a time into the bag")
    in_range("--clock", args.clock, 0.0, MAX_CLOCK_HZ, unit="Hz",
             what="a /clock rate", note="(0: no /clock)")
    whole("--queue-depth", args.queue_depth, 0, MAX_QUEUE_DEPTH, unit="messages",
          what="a history depth:")
    if args.wait_for != "all":
        whole("--wait-for", args.wait_for, 0, MAX_WAIT_FOR, unit="subscriptions",
              what="a count:")
    in_range("--wait-timeout", args.wait_timeout, 0.0, MAX_WAIT_S, unit="s",
             what="a waiting time")


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
    problems = found.problems + source.repaired()[0]
    for problem in problems:
        print(f"drill_sim_replay: incomplete bag: {problem}", file=sys.stderr)
    if problems and not args.partial:
        source.close()
        print("drill_sim_replay: the bag is incomplete: refused (pass --partial to replay "
              "its readable part)", file=sys.stderr)
        return 1
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
        started = time.monotonic()
        while not stop:
            player.play_once(stop, progress)
            if not args.loop:
                break
        progress.close()
        wall_s = time.monotonic() - started
        player.wait_acked(10.0)
        print(f"drill_sim_replay: published {player.sent} messages", file=sys.stderr)
        span_s = (found.end_ns - found.start_ns) * 1e-9 - args.start_offset
        if player.held_back and not args.loop and wall_s > 0 and span_s > 0:
            print(f"drill_sim_replay: held back by its subscribers (a keep-all history was "
                  f"full {player.held_back} times): played at {span_s / wall_s:.2f}x of the "
                  f"recording, asked {args.rate:g}x; nothing was dropped", file=sys.stderr)
        if player.problems and not args.partial:
            return 1                                # damage the bag's info did not show
    finally:
        player.destroy_node()
        shutdown()
    return 0


def _count_or_all(text: str) -> int | str:
    """argparse ``type`` of --wait-for: a count, or ``all`` (one subscription on every topic)."""
    return "all" if text.strip() == "all" else integer(text)


def main(argv: list[str] | None = None) -> int:
    """The ``drill_sim_replay`` console script: ROS arguments are left to rclpy."""
    argv = sys.argv if argv is None else argv
    parser = Parser(prog="drill_sim_replay", description=DESCRIPTION)
    add_arguments(parser)
    parser.set_defaults(argv=argv)
    try:
        return run(parser.parse_args(join_negative_values(without_ros_args(argv)[1:])))
    except UsageError as exc:
        print(f"drill_sim_replay: error: {exc}", file=sys.stderr)
        return 2


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
