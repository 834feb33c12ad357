"""The recorder behind ``drill_sim_record`` (its command line: ``drill_sim.cli.record``).

Like ``ros2 bag record``: the listed topics, a regular expression, or all; topics that appear
later are picked up as they are discovered. Subscriptions are raw (the CDR bytes go to the bag
untouched) and adapt their QoS to the publishers, whose offered profiles are written beside the
topic. Messages a publisher sent that never arrived are counted from its sequence numbers,
printed at the end and written into the bag (``bag.losses``). A stop request closes the bag
properly; a killed recorder loses at most the last second, and ``drill_sim bag repair``
restores the rest.
"""

from __future__ import annotations

import re
import time

import rclpy
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.type_support import check_is_valid_msg_type

from ..bag.losses import SequenceGaps
from ..bag.writer import BagError, BagWriter
from ..terminal import StatusLine
from .topics import KEEP_ALL, UnknownType, message_class, profile_dict, subscription_qos


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
    """Raw subscriptions to every selected topic that has a publisher, taken by the recorder
    itself (not an executor, which hands out no message info), so each message comes with its
    publisher's sequence number and a gap is counted (``bag.losses``)."""

    TAKE_LIMIT = 1000          # most messages taken per topic in one round

    def __init__(self, writer: BagWriter, select: TopicSelection, depth: int) -> None:
        super().__init__("drill_sim_record")
        self.writer, self.select, self.depth = writer, select, depth
        self.subscriptions_by_topic: dict[str, object] = {}
        self.skipped: set[str] = set()
        self.error: str | None = None
        self.gaps = SequenceGaps()
        self.start_ns: int | None = None
        self._takers: list[tuple[str, object, type]] = []
        self._context = self.context.handle
        self._wait_set = None

    def discover(self) -> None:
        """Subscribe to the selected topics that appeared since the last call."""
        added = False
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
                check_is_valid_msg_type(cls)        # loads the type support
            except UnknownType as exc:
                self.get_logger().warning(f"not recording {topic}: {exc}")
                self.skipped.add(topic)
                continue
            self.writer.add_topic(topic, types[0],
                                  [profile_dict(p.qos_profile) for p in publishers])
            with self.handle:
                handle = _rclpy.Subscription(
                    self.handle, cls, topic,
                    subscription_qos(publishers, self.depth).get_c_qos_profile())
            self.subscriptions_by_topic[topic] = handle
            self._takers.append((topic, handle, cls))
            added = True
            self.get_logger().info(f"recording {topic} ({types[0]})")
        if added:
            if self._wait_set is not None:
                self._wait_set.destroy_when_not_in_use()
            self._wait_set = _rclpy.WaitSet(len(self._takers), 0, 0, 0, 0, 0, self._context)

    def wait(self, timeout_s: float) -> None:
        """Until a message has arrived on a recorded topic, or ``timeout_s`` [s]."""
        if self._wait_set is None:
            time.sleep(timeout_s)
            return
        with self._context:
            self._wait_set.clear_entities()
            for _, handle, _ in self._takers:
                self._wait_set.add_subscription(handle)
            self._wait_set.wait(max(0, int(timeout_s * 1e9)))

    def take(self) -> int:
        """Write what has arrived (at most TAKE_LIMIT per topic); the number taken."""
        taken = 0
        write, note = self.writer.write, self.gaps.note
        for topic, handle, cls in self._takers:
            for _ in range(self.TAKE_LIMIT):
                got = handle.take_message(cls, True)
                if got is None:
                    break
                data, info = got
                now = time.time_ns()
                if self.start_ns is None:
                    self.start_ns = now
                taken += 1
                sequence = info.get("publication_sequence_number")
                if sequence:
                    last = self.gaps.last_sequence(topic)
                    publishers = handle.get_publisher_count() \
                        if last is not None and sequence > last + 1 else 1
                    note(topic, sequence, (now - self.start_ns) * 1e-9, publishers)
                if self.error is None:
                    try:
                        write(topic, data, now)
                    except (OSError, BagError) as exc:
                        self.error = f"recording stopped: {exc}"
        return taken

    def close_subscriptions(self) -> None:
        for _, handle, _ in self._takers:
            handle.destroy_when_not_in_use()
        if self._wait_set is not None:
            self._wait_set.destroy_when_not_in_use()
        self._takers.clear()


def record(writer: BagWriter, select: TopicSelection, stop: list[int], *,
           queue_depth: int = KEEP_ALL, duration_s: float = 0.0,
           discovery_period_s: float = 0.1) -> tuple[str | None, SequenceGaps]:
    """Record into ``writer`` until ``stop`` fills (see ``stopping.init_stoppable``, which must
    have started rclpy), ``duration_s`` of wall time passes (0: no limit) or writing fails;
    then shut rclpy down, write what was lost (``recording`` metadata) and close the bag.
    Returns what stopped the recording early (or None) and the gaps found."""
    node = TopicRecorder(writer, select, queue_depth)
    status = _Status(writer)
    end = time.monotonic() + duration_s if duration_s else float("inf")
    next_discovery = 0.0
    try:
        while not stop and node.error is None and time.monotonic() < end:
            now = time.monotonic()
            if now >= next_discovery:
                node.discover()
                status.show(now)
                next_discovery = now + discovery_period_s
            node.wait(min(discovery_period_s, max(next_discovery - time.monotonic(), 0.0)))
            node.take()
        _drain(node)
    finally:
        status.close()
        gaps = node.gaps
        node.close_subscriptions()
        node.destroy_node()
        rclpy.try_shutdown()
        try:
            writer.add_metadata("recording", gaps.record())
            writer.close()
        except (OSError, BagError) as exc:
            node.error = node.error or f"closing the bag failed: {exc}"
    return node.error, gaps


def _drain(node: TopicRecorder, quiet_s: float = 0.05, limit_s: float = 2.0) -> None:
    """On stop, take what has already arrived: until nothing comes for ``quiet_s``."""
    end = time.monotonic() + limit_s
    while time.monotonic() < end:
        node.wait(quiet_s)
        if node.take() == 0:
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
