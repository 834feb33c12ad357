"""The rig node's command subscriptions, taken by the tick instead of dispatched by the executor.

Under rclpy's EventsExecutor every arriving message is one event, and the timer's events queue
behind them: a flood of commands from another process stopped the ticks for seconds. Here the
command subscriptions are raw and never handed to the executor; each tick takes at most
``limit`` messages per topic (the subscription's history depth, so one take empties a full
queue), decodes them with ``wire.cdr`` and the node applies them in arrival order. However fast
commands come, a tick does a bounded amount of work for them. What the executor still
dispatches (timers, services, parameter requests) arrives at human rates.

What is dropped is counted: ``lost`` commands never reached the node (its subscription keeps
the latest ``depth`` per topic, and a publisher that outruns the ticks overwrites older ones;
counted from gaps in the publisher's sequence numbers while a topic has one publisher, which
is the case a flood comes from), and the node counts the ones it took but that a later command
of the same topic replaced within the same tick.

With ``owner_first`` (the node's ``command_owner: first``, as ros2_control lets one controller
claim a command interface) each topic belongs to the first publisher whose command is taken:
the others' are refused and counted by publisher, and their gaps are counted per publisher,
until ``release`` frees the topic (its owner left the graph). Telling publishers apart needs
the publisher's GID, which only ``publisher_take`` reads.
"""

from __future__ import annotations

from collections import Counter
from typing import NamedTuple

from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.type_support import check_is_valid_msg_type

from ..wire import WireError, rig_topics
from ..wire.cdr_decode import JointCommand, command_decoder
from ..wire.rig_topics import RigTopic
from .publisher_take import PublisherTake
from .topics import message_class, rclpy_qos


class Command(NamedTuple):
    """One command message as taken: its topic, its bytes and what they hold. A named tuple:
    in lockstep one is built every tick, ~1 us cheaper than a frozen dataclass."""

    topic: RigTopic
    data: bytes                      # the CDR bytes as received
    frame_id: str
    sec: int
    nanosec: int
    six: tuple[float, ...] | JointCommand   # the six float64 (``wire.cdr.VECTOR_FIELDS``
                                            # order); a JointState's names and arrays


class CommandInbox:
    """Raw subscriptions to the table's command topics on ``node``, outside any executor.

    reliability: the node's ``qos_reliability``; limit: most messages taken per topic and tick;
    owner_first: one publisher per topic (the module's doc). ``received``, ``lost``,
    ``undecodable`` and ``refused`` count since start."""

    def __init__(self, node: Node, reliability: str, limit: int | None = None,
                 owner_first: bool = False) -> None:
        self._subs: list[tuple[RigTopic, object, type]] = []
        for t in rig_topics.COMMANDS:
            qos = t.qos_for(reliability)
            cls = message_class(t.type_name)
            check_is_valid_msg_type(cls)             # loads the type support
            with node.handle:
                handle = _rclpy.Subscription(node.handle, cls, t.name,
                                             rclpy_qos(qos).get_c_qos_profile())
            self._subs.append((t, handle, cls))
        self.limit = limit or max(t.qos_for(reliability).depth for t in rig_topics.COMMANDS)
        self.received = self.lost = self.undecodable = self.refused = 0
        # owner_first: each topic's owner (publisher GID), and refusals not yet reported
        self.owners: dict[str, bytes] = {}
        self.refused_from: Counter[tuple[str, bytes]] = Counter()
        self._publisher_take = PublisherTake() if owner_first else None
        self.last_undecodable = ""              # why the last one was: "topic: reason"
        self._last_sequence: dict[str, int] = {}
        self._context = node.context.handle
        self._watched = [h for _, h, _ in self._subs]
        # per topic, what a take needs, bound once: the take itself and the decoder of its type
        self._takers = [(t, h.take_message, cls, command_decoder(t.type_name))
                        for t, h, cls in self._subs]
        self._handles = {t.name: h for t, h, _ in self._subs}
        self._wait_set = _rclpy.WaitSet(len(self._subs), 0, 0, 0, 0, 0, self._context)

    def wait_on(self, names: tuple[str, ...] | None) -> None:
        """Let ``wait`` wake only for these topics (table names; None: every command topic).
        A wait costs ~3 us of CPU more per topic it watches (Fast DDS attaches and detaches a
        condition for each), and in lockstep only the lockstep topics release a tick."""
        self._watched = [h for t, h, _ in self._subs if names is None or t.name in names]
        self._wait_set.destroy_when_not_in_use()
        self._wait_set = _rclpy.WaitSet(len(self._watched), 0, 0, 0, 0, 0, self._context)

    def wait(self, timeout_s: float) -> None:
        """Block until a command has arrived on a watched topic (``wait_on``), or
        ``timeout_s`` [s] passed: the middleware wakes the thread, so a lockstep wait costs
        no CPU and no polling delay."""
        ws = self._wait_set
        with self._context:
            ws.clear_entities()
            for handle in self._watched:
                ws.add_subscription(handle)
            ws.wait(max(0, int(timeout_s * 1e9)))

    def take(self) -> list[Command]:
        """What arrived since the last call, at most ``limit`` per topic, each topic's in
        arrival order; undecodable messages are counted and left out."""
        if self._publisher_take is not None:
            return self._take_owned()
        out: list[Command] = []
        for t, take, cls, decode in self._takers:
            for _ in range(self.limit):
                taken = take(cls, True)
                if taken is None:
                    break
                data, info = taken
                self.received += 1
                sequence = info.get("publication_sequence_number")
                if sequence:
                    self._count_gap(t.name, sequence)
                self._keep(out, t, data, decode)
        return out

    def _take_owned(self) -> list[Command]:
        """``take`` with one publisher per topic: the first one's commands, the others'
        refused (counted in ``refused`` and, until reported, ``refused_from``)."""
        out: list[Command] = []
        take = self._publisher_take.take
        for t, _, _, decode in self._takers:
            handle = self._handles[t.name]
            for _ in range(self.limit):
                taken = take(handle)
                if taken is None:
                    break
                self.received += 1
                owner = self.owners.setdefault(t.name, taken.publisher)
                if taken.publisher != owner:
                    self.refused += 1
                    self.refused_from[(t.name, taken.publisher)] += 1
                    continue
                if taken.sequence:           # one publisher's numbering: exact
                    self._count_gap(t.name, taken.sequence, owned=True)
                self._keep(out, t, taken.data, decode)
        return out

    def _keep(self, out: list[Command], t: RigTopic, data: bytes, decode) -> None:
        """The message ``data`` of topic ``t`` decoded onto ``out``; counted if it does not
        decode."""
        try:
            frame_id, sec, nanosec, six = decode(data)
        except WireError as exc:
            self.undecodable += 1
            self.last_undecodable = f"{t.name}: {exc}"
            return
        out.append(Command(t, data, frame_id, sec, nanosec, six))

    def release(self, name: str) -> None:
        """Topic ``name`` (table name) is free again: the next publisher's command owns it."""
        self.owners.pop(name, None)
        self._last_sequence.pop(name, None)

    def _count_gap(self, name: str, sequence: int, owned: bool = False) -> None:
        """Messages overwritten before they were taken: gaps in one publisher's numbering
        (while the topic has one publisher; a middleware that numbers nothing reports 0)."""
        last = self._last_sequence.get(name)
        self._last_sequence[name] = sequence
        if (last is not None and sequence > last + 1
                and (owned or self._handles[name].get_publisher_count() == 1)):
            self.lost += sequence - last - 1

    def destroy(self) -> None:
        if self._publisher_take is not None:
            self._publisher_take.close()
        self._wait_set.destroy_when_not_in_use()
        for _, handle, _ in self._subs:
            handle.destroy_when_not_in_use()
        self._subs, self._watched, self._takers, self._handles = [], [], [], {}
