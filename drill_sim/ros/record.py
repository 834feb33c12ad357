"""The recorder behind ``drill_sim_record`` (its command line: ``drill_sim.cli.record``).

Like ``ros2 bag record``: the listed topics, a regular expression, or all; topics that appear
later are picked up as they are discovered. Subscriptions are raw (the CDR bytes go to the bag
untouched) and adapt their QoS to the publishers, whose offered profiles are written beside the
topic. A stop request closes the bag properly; a killed recorder loses at most the last
second, and ``drill_sim bag repair`` restores the rest.
"""

from __future__ import annotations

import re
import time

import rclpy
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.task import Future

from ..bag.writer import BagError, BagWriter
from ..terminal import StatusLine
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


def record(writer: BagWriter, select: TopicSelection, stop: list[int], *,
           queue_depth: int = 1000, duration_s: float = 0.0,
           discovery_period_s: float = 0.1) -> str | None:
    """Record into ``writer`` until ``stop`` fills (see ``stopping.init_stoppable``, which must
    have started rclpy), ``duration_s`` of wall time passes (0: no limit) or writing fails;
    then shut rclpy down and close the bag. Returns what stopped the recording early, or None.
    """
    node = TopicRecorder(writer, select, queue_depth)
    executor = EventsExecutor()
    executor.add_node(node)
    status = _Status(writer)
    end = time.monotonic() + duration_s if duration_s else float("inf")
    next_discovery = 0.0
    never = Future()
    try:
        while not stop and node.error is None and time.monotonic() < end:
            now = time.monotonic()
            if now >= next_discovery:
                node.discover()
                status.show(now)
                next_discovery = now + discovery_period_s
            # many messages per call, dispatched in C++ (spin_once returns after each one)
            executor.spin_until_future_complete(never, timeout_sec=discovery_period_s)
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
    return node.error


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
