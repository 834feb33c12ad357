"""``drill_sim_replay BAG``: publishes a bag's messages with their recorded timing.

Like ``ros2 bag play``: any rosbag2 MCAP bag (or bare ``.mcap``) whose message types are
installed here; each topic is published with the QoS its recorded publishers offered, the
CDR bytes as they are. Playback starts once subscribers have matched, so none of the first
messages is lost. ``--clock`` publishes ``/clock`` from the recorded times for nodes running
with ``use_sim_time``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import rclpy
import yaml
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.utilities import remove_ros_args
from rosgraph_msgs.msg import Clock

from ..bag.mcap_scan import McapScan
from ..bag.reader import info, mcap_files
from ..bag.writer import BagError
from ..cli.progress import StatusLine
from ..wire import cdr, rig_topics
from .stopping import init_stoppable
from .topics import UnknownType, message_class, profile_from_dicts, rclpy_qos


class Player(Node):
    """Publishers for the bag's topics and the timed loop that feeds them."""

    def __init__(self, bag: Path, topics: dict[str, tuple[str, str]], start_ns: int,
                 args: argparse.Namespace) -> None:
        super().__init__("drill_sim_replay")
        self.bag, self.bag_start_ns, self.args = bag, start_ns, args
        self.publishers_by_topic = {}
        for name, (type_name, qos_text) in topics.items():
            try:
                cls = message_class(type_name)
            except UnknownType as exc:
                self.get_logger().warning(f"not replaying {name}: {exc}")
                continue
            try:
                profiles = yaml.safe_load(qos_text) if qos_text else None
            except yaml.YAMLError:
                profiles = None
            qos = profile_from_dicts(profiles if isinstance(profiles, list) else None,
                                     args.queue_depth)
            self.publishers_by_topic[name] = self.create_publisher(cls, name, qos)
        clock = rig_topics.CLOCK_TOPIC
        self.clock_pub = self.create_publisher(Clock, clock.name, rclpy_qos(clock.qos)) \
            if args.clock else None
        self.encode_clock = cdr.clock()
        self.sent = 0

    # ---- before: subscribers -----------------------------------------------------------
    def wait_for_subscribers(self, stop: list[int], settle_s: float = 0.25) -> str | None:
        """Until every subscription the graph knows on our topics has matched, at least
        ``--wait-for`` have, and no new one has appeared for ``settle_s`` (a recorder
        subscribes to several topics at once, and they are discovered one by one); None
        then, or what was missing when ``--wait-timeout`` passed."""
        end = time.monotonic() + self.args.wait_timeout
        last, changed = None, time.monotonic()
        while not stop:
            matched = sum(p.get_subscription_count() for p in self.publishers_by_topic.values())
            known = sum(self.count_subscribers(t) for t in self.publishers_by_topic)
            if (matched, known) != last:
                last, changed = (matched, known), time.monotonic()
            if matched >= self.args.wait_for and matched >= known \
                    and time.monotonic() - changed >= settle_s:
                return None
            if time.monotonic() >= end:
                return (f"{matched} subscriptions matched of {max(known, self.args.wait_for)} "
                        f"waited for after {self.args.wait_timeout:g} s (a subscription "
                        "asking for more than the recorded QoS offers never matches)")
            time.sleep(0.01)
        return None

    # ---- playing -----------------------------------------------------------------------
    def play_once(self, stop: list[int], progress) -> None:
        """One pass over the bag from ``--start-offset``, paced by the log times."""
        rate, offset_ns = self.args.rate, int(self.args.start_offset * 1e9)
        clock_period = 1.0 / self.args.clock if self.args.clock else math.inf
        first: int | None = None
        wall0 = next_clock = 0.0
        publishers = self.publishers_by_topic
        problems: list[str] = []
        for file in mcap_files(self.bag):
            with McapScan(file, problems) as scan:
                topics = scan.channels.topics
                for cid, log, _, data in scan.messages():
                    pub = publishers.get(topics.get(cid))
                    if pub is None:
                        continue
                    if first is None:
                        first = self.bag_start_ns + offset_ns
                        wall0 = next_clock = time.monotonic()
                    if log < first:
                        continue                        # before the start offset
                    due = wall0 + (log - first) * 1e-9 / rate
                    while True:                         # wait, keeping /clock going
                        now = time.monotonic()
                        if now >= next_clock:
                            self._publish_clock(first + (now - wall0) * rate * 1e9)
                            next_clock = now + clock_period
                        if now >= due or stop:
                            break
                        time.sleep(min(due, next_clock) - now)
                    if stop:
                        return
                    pub.publish(bytes(data))
                    self.sent += 1
                    progress(log)
        for problem in problems:
            self.get_logger().warning(problem)

    def _publish_clock(self, bag_ns: float) -> None:
        if self.clock_pub is not None:
            sec, nsec = divmod(int(bag_ns), 1_000_000_000)
            self.clock_pub.publish(self.encode_clock(sec, nsec))

    def wait_acked(self, timeout_s: float) -> None:
        """Let reliable subscribers receive the last messages before the publishers go."""
        for pub in self.publishers_by_topic.values():
            pub.wait_for_all_acked(Duration(seconds=timeout_s))


def _arguments(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="drill_sim_replay",
        description="Publish a bag's messages with their recorded timing "
                    "(what `ros2 bag play` does).")
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
    parser.add_argument("--wait-for", type=int, default=1, metavar="N",
                        help="wait for at least N matched subscriptions before playing "
                             "(default 1; 0 = do not wait)")
    parser.add_argument("--wait-timeout", type=float, default=30.0, metavar="S",
                        help="play anyway after S seconds of waiting (default 30)")
    args = parser.parse_args(argv)
    checks = [("--rate", args.rate, args.rate > 0 and math.isfinite(args.rate), "> 0"),
              ("--start-offset", args.start_offset,
               args.start_offset >= 0 and math.isfinite(args.start_offset), ">= 0"),
              ("--clock", args.clock, args.clock >= 0 and math.isfinite(args.clock), "> 0 Hz"),
              ("--queue-depth", args.queue_depth, args.queue_depth >= 1, ">= 1"),
              ("--wait-for", args.wait_for, args.wait_for >= 0, ">= 0"),
              ("--wait-timeout", args.wait_timeout, args.wait_timeout >= 0, ">= 0 s")]
    for name, value, ok, expected in checks:
        if not ok:
            parser.error(f"{name} = {value}: expected a number {expected}")
    return args


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv if argv is None else argv
    args = _arguments(remove_ros_args(argv)[1:])
    bag = Path(args.bag)
    try:
        found = info(bag)
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
    stop = init_stoppable(argv)
    player = Player(bag, topics, found.start_ns, args)
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
