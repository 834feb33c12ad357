"""The player behind ``drill_sim_replay`` (its command line: ``drill_sim.cli.replay``).

Like ``ros2 bag play``: any rosbag2 MCAP bag (or bare ``.mcap``) whose message types are
installed here; each topic is published with the QoS its recorded publishers offered, the
CDR bytes as they are. Playback starts once subscribers have matched (with
``wait_for_every_topic``, one on every topic played), so none of the first messages is lost.
A clock rate publishes ``/clock`` from the recorded times for nodes running with
``use_sim_time``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import yaml
from rclpy.duration import Duration
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rosgraph_msgs.msg import Clock

from ..bag.bag import Bag
from ..wire import cdr, rig_topics
from .topics import KEEP_ALL, UnknownType, message_class, profile_from_dicts, rclpy_qos


@dataclass(frozen=True)
class PlayOptions:
    """How to play: the options of ``drill_sim_replay``, in their units."""

    rate: float = 1.0             # playback speed relative to the recording
    start_offset_s: float = 0.0   # start this far into the bag
    clock_hz: float = 0.0         # /clock publishing rate; 0: no /clock
    queue_depth: int = 0          # publisher history per topic [messages]; 0: keep all
    wait_for: int = 1             # matched subscriptions to wait for before playing
    wait_for_every_topic: bool = False   # and at least one on every topic played
    wait_timeout_s: float = 30.0  # play anyway after this long waiting


class Player(Node):
    """Publishers for the bag's topics and the timed loop that feeds them."""

    def __init__(self, bag: Bag, topics: dict[str, tuple[str, str]], start_ns: int,
                 options: PlayOptions) -> None:
        super().__init__("drill_sim_replay")
        self.bag, self.bag_start_ns, self.options = bag, start_ns, options
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
                                     options.queue_depth)
            self.publishers_by_topic[name] = self.create_publisher(cls, name, qos)
        clock = rig_topics.CLOCK_TOPIC
        self.clock_pub = self.create_publisher(Clock, clock.name, rclpy_qos(clock.qos)) \
            if options.clock_hz else None
        self.encode_clock = cdr.clock()
        self.sent = 0
        self.held_back = 0          # publishes the middleware refused while a history was full
        self.problems: list[str] = []             # damage met while playing

    # ---- before: subscribers -----------------------------------------------------------
    def wait_for_subscribers(self, stop: list[int], settle_s: float = 0.25) -> str | None:
        """Until every subscription the graph knows on our topics has matched, at least
        ``wait_for`` have (and, with ``wait_for_every_topic``, at least one on every topic),
        and no new one has appeared for ``settle_s`` (a recorder subscribes to several topics
        at once, and they are discovered one by one); None then, or what was missing when
        ``wait_timeout_s`` passed."""
        end = time.monotonic() + self.options.wait_timeout_s
        last, changed = None, time.monotonic()
        while not stop:
            per_topic = {t: p.get_subscription_count()
                         for t, p in self.publishers_by_topic.items()}
            matched = sum(per_topic.values())
            known = sum(self.count_subscribers(t) for t in self.publishers_by_topic)
            alone = sorted(t for t, n in per_topic.items() if n == 0) \
                if self.options.wait_for_every_topic else []
            if (matched, known) != last:
                last, changed = (matched, known), time.monotonic()
            if matched >= self.options.wait_for and matched >= known and not alone \
                    and time.monotonic() - changed >= settle_s:
                return None
            if time.monotonic() >= end:
                return (f"{matched} subscriptions matched of "
                        f"{max(known, self.options.wait_for)} waited for after "
                        f"{self.options.wait_timeout_s:g} s" + (
                            f", none on {len(alone)} topics ({', '.join(alone)})"
                            if alone else "") + " (a subscription asking for more than the "
                        "recorded QoS offers never matches)")
            time.sleep(0.01)
        return None

    # ---- playing -----------------------------------------------------------------------
    def play_once(self, stop: list[int], progress) -> None:
        """One pass over the bag from ``start_offset_s``, paced by the log times."""
        rate, offset_ns = self.options.rate, int(self.options.start_offset_s * 1e9)
        clock_period = 1.0 / self.options.clock_hz if self.options.clock_hz else math.inf
        first: int | None = None
        wall0 = next_clock = 0.0
        last_clock = 0.0                            # the last /clock of this pass [ns]
        publishers = self.publishers_by_topic
        problems: list[str] = []
        for scan in self.bag.scans(problems):
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
                    if now >= next_clock:   # never past the message about to go out (a
                        # late wake-up must not put /clock beyond the recorded times), never back
                        last_clock = max(last_clock, min(first + (now - wall0) * rate * 1e9, log))
                        self._publish_clock(last_clock)
                        next_clock = now + clock_period
                    if now >= due or stop:
                        break
                    time.sleep(min(due, next_clock) - now)
                if stop:
                    return
                if not self._publish(pub, bytes(data), stop):
                    return
                self.sent += 1
                progress(log)
        for problem in problems:
            if problem not in self.problems:
                self.problems.append(problem)
                self.get_logger().warning(problem)

    def _publish(self, pub, data: bytes, stop: list[int]) -> bool:
        """Publish, waiting while a keep-all history is full (a reliable subscriber has not
        taken the earlier messages yet: the middleware refuses after blocking a while); False
        if asked to stop meanwhile."""
        while True:
            try:
                pub.publish(data)
                return True
            except _rclpy.RCLError:
                if self.options.queue_depth != KEEP_ALL:
                    raise
                self.held_back += 1
                if stop:
                    return False
                time.sleep(0.001)

    def _publish_clock(self, bag_ns: float) -> None:
        if self.clock_pub is not None:
            sec, nsec = divmod(int(bag_ns), 1_000_000_000)
            self.clock_pub.publish(self.encode_clock(sec, nsec))

    def wait_acked(self, timeout_s: float) -> None:
        """Let reliable subscribers receive the last messages before the publishers go."""
        for pub in self.publishers_by_topic.values():
            pub.wait_for_all_acked(Duration(seconds=timeout_s))
