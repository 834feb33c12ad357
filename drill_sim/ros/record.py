"""``drill_sim_record``: records topics of the ROS graph into a rosbag2 MCAP bag.

Like ``ros2 bag record``: the listed topics, a regular expression, or all; topics that appear
later are picked up as they are discovered. Subscriptions are raw (the CDR bytes go to the bag
untouched) and adapt their QoS to the publishers, whose offered profiles are written beside the
topic. Ctrl-C or SIGTERM closes the bag properly; a killed recorder loses at most the last
second, and ``drill_sim bag repair`` restores the rest.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from datetime import datetime
from pathlib import Path

import rclpy
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.task import Future
from rclpy.utilities import remove_ros_args

from .. import __version__
from ..bag.writer import BagError, BagWriter
from ..terminal import StatusLine
from .stopping import init_stoppable
from .topics import UnknownType, message_class, profile_dict, subscription_qos


class TopicSelection:
    """Which topics to record: exact names, a regular expression, or all (minus exclusions)."""

    def __init__(self, topics: list[str], regex: str | None, all_topics: bool,
                 exclude: str | None) -> None:
        self.names = {t if t.startswith("/") else "/" + t for t in topics}
        self.regex = re.compile(regex) if regex else None
        self.all = all_topics
        self.exclude = re.compile(exclude) if exclude else None

    def __call__(self, topic: str) -> bool:
        if self.exclude is not None and self.exclude.search(topic):
            return False
        return self.all or topic in self.names or bool(
            self.regex is not None and self.regex.search(topic))


class TopicRecorder(Node):
    """Subscribes raw to every selected topic that has a publisher and writes what arrives."""

    def __init__(self, writer: BagWriter, select: TopicSelection, depth: int) -> None:
        super().__init__("drill_sim_record")
        self.writer, self.select, self.depth = writer, select, depth
        self.subscriptions_by_topic: dict[str, object] = {}
        self.skipped: set[str] = set()
        self.error: str | None = None

    def discover(self) -> None:
        """Subscribe to the selected topics that appeared since the last call."""
        for topic, types in self.get_topic_names_and_types():
            if topic in self.subscriptions_by_topic or topic in self.skipped \
                    or not self.select(topic):
                continue
            publishers = self.get_publishers_info_by_topic(topic)
            if not publishers:
                continue                        # only subscribers so far: nothing to record
            if len(types) > 1:
                self.get_logger().warning(f"{topic} carries several types {types}; recording "
                                          f"{types[0]}")
            try:
                cls = message_class(types[0])
            except UnknownType as exc:
                self.get_logger().warning(f"not recording {topic}: {exc}")
                self.skipped.add(topic)
                continue
            self.writer.add_topic(topic, types[0],
                                  [profile_dict(p.qos_profile) for p in publishers])
            self.subscriptions_by_topic[topic] = self.create_subscription(
                cls, topic, self._callback(topic), subscription_qos(publishers, self.depth),
                raw=True)
            self.get_logger().info(f"recording {topic} ({types[0]})")

    def _callback(self, topic: str):
        write = self.writer.write

        def on_message(data: bytes) -> None:
            if self.error is not None:
                return
            try:
                write(topic, data, time.time_ns())
            except (OSError, BagError) as exc:
                self.error = f"recording stopped: {exc}"
        return on_message


def _arguments(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="drill_sim_record",
        description="Record topics into a rosbag2 MCAP bag (what `ros2 bag record` does).")
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
    args = parser.parse_args(argv)
    if not (args.topics or args.all or args.regex):
        parser.error("name topics, or give --regex or --all")
    for name, value in (("--max-bag-duration", args.max_bag_duration),
                        ("--max-bag-size", args.max_bag_size), ("--duration", args.duration)):
        if not value >= 0:
            parser.error(f"{name} = {value}: expected a number >= 0")
    if not (args.queue_depth >= 1 and args.discovery_period > 0):
        parser.error("--queue-depth must be >= 1 and --discovery-period > 0")
    if args.regex or args.exclude:
        try:
            re.compile(args.regex or ""), re.compile(args.exclude or "")
        except re.error as exc:
            parser.error(f"bad regular expression: {exc}")
    return args


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv if argv is None else argv
    args = _arguments(remove_ros_args(argv)[1:])
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
    node = TopicRecorder(writer, TopicSelection(args.topics, args.regex, args.all, args.exclude),
                         args.queue_depth)
    executor = EventsExecutor()
    executor.add_node(node)
    status = _Status(writer)
    end = time.monotonic() + args.duration if args.duration else float("inf")
    next_discovery = 0.0
    never = Future()
    try:
        while not stop and node.error is None and time.monotonic() < end:
            now = time.monotonic()
            if now >= next_discovery:
                node.discover()
                status.show(now)
                next_discovery = now + args.discovery_period
            # many messages per call, dispatched in C++ (spin_once returns after each one)
            executor.spin_until_future_complete(never, timeout_sec=args.discovery_period)
        _drain(executor, writer)
    finally:
        status.close()
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
        try:
            writer.close()
        except (OSError, BagError) as exc:
            node.error = node.error or f"closing the bag failed: {exc}"
    counts = ", ".join(f"{t.name} {t.count}" for t in writer.topics.values()) or "no topics"
    print(f"drill_sim_record: {sum(t.count for t in writer.topics.values())} messages in "
          f"{output} ({counts})", file=sys.stderr)
    if node.error is not None:
        print(f"drill_sim_record: {node.error}", file=sys.stderr)
        return 1
    return 0


def _drain(executor: EventsExecutor, writer: BagWriter, quiet_s: float = 0.05,
           limit_s: float = 2.0) -> None:
    """On stop, take what has already arrived: spin until nothing comes for ``quiet_s``."""
    end = time.monotonic() + limit_s
    while time.monotonic() < end:
        before = sum(t.count for t in writer.topics.values())
        executor.spin_once(timeout_sec=quiet_s)
        if sum(t.count for t in writer.topics.values()) == before:
            return


class _Status:
    """Topics, messages and rate on a terminal line, once a second."""

    def __init__(self, writer: BagWriter) -> None:
        self.writer = writer
        self.line = StatusLine(1.0)
        self.last = (time.monotonic(), 0)

    def show(self, now: float) -> None:
        if not self.line.due():
            return
        total = sum(t.count for t in self.writer.topics.values())
        rate = (total - self.last[1]) / max(now - self.last[0], 1e-9)
        self.last = (now, total)
        self.line.show(f"recording {len(self.writer.topics)} topics: {total} messages, "
                       f"{rate:8.0f} msg/s ")

    def close(self) -> None:
        self.line.close()


if __name__ == "__main__":
    sys.exit(main())
