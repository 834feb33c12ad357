"""The rig's exclusive command mode (``command_owner: first``) as the log and /diagnostics see
it: which node owns each command topic, whose commands were refused, and when an owner left.

The inbox (``commands.CommandInbox`` with ``owner_first``) decides by publisher GID; this puts
node names on the GIDs from the graph and says what happened, at most once a second.
"""

from __future__ import annotations

import time

from rclpy.node import Node

from ..wire import rig_topics
from .commands import CommandInbox
from .publisher_take import endpoint_gid
from .topics import NOT_YET_NAMED, publisher_names

REPORT_PERIOD_S = 1.0       # refusals are summed and said at most this often
# an owner the graph never showed is taken to have left after this long [s] (discovery of a
# publisher lags its first message by milliseconds, not seconds)
NEVER_SEEN_S = 5.0
LEFT = "(a publisher that has left)"


class CommandOwnership:
    """Names and reports the owners the inbox keeps; ``check_graph`` frees the topics whose
    owner's publisher is gone (call it at the diagnostics period)."""

    def __init__(self, node: Node, inbox: CommandInbox) -> None:
        self._node, self._inbox = node, inbox
        self._names: dict[str, str] = {}       # topic -> owner node, once named
        self._unseen_since: dict[str, float] = {}   # topic -> when its owner was first missed
        self._next_report = 0.0
        self._resolved = {t.name: node.resolve_topic_name(t.name) for t in rig_topics.COMMANDS}

    def _publishers(self, topic: str) -> dict[bytes, str]:
        infos = self._node.get_publishers_info_by_topic(self._resolved[topic])
        return dict(zip((endpoint_gid(i) for i in infos), publisher_names(infos), strict=True))

    def _name(self, topic: str, gid: bytes) -> str:
        return self._publishers(topic).get(gid, LEFT)

    def after_take(self) -> None:
        """Say each new owner at once, and the commands refused since the last report."""
        inbox, log = self._inbox, self._node.get_logger()
        for topic, gid in inbox.owners.items():
            if topic not in self._names:
                name = self._name(topic, gid)
                if name in (NOT_YET_NAMED, LEFT):
                    name = NOT_YET_NAMED       # discovery lags the first message: named later
                else:
                    log.info(f"{topic}: taking only {name}'s commands (command_owner first)")
                self._names[topic] = name
        now = time.monotonic()
        if not inbox.refused_from or now < self._next_report:
            return
        self._report()
        self._next_report = now + REPORT_PERIOD_S

    def _report(self, only: str | None = None) -> None:
        """Say the refusals not yet said (on topic ``only``, or every topic), and forget them."""
        refused = self._inbox.refused_from
        for (topic, gid), count in sorted(refused.items()):
            if only is not None and topic != only:
                continue
            self._node.get_logger().warning(
                f"refused {count} command{'s' if count > 1 else ''} on {topic} from "
                f"{self._name(topic, gid)}: {self._names.get(topic, NOT_YET_NAMED)} owns it "
                "(command_owner first); stop the other program, or stop the owner to hand the "
                "topic over")
            del refused[(topic, gid)]

    def check_graph(self) -> tuple[tuple[str, str], ...]:
        """Free the topics whose owner's publisher has left (said in the log), name owners
        that were not named yet; the owners now, (topic, node)."""
        inbox, log = self._inbox, self._node.get_logger()
        for topic, gid in list(inbox.owners.items()):
            publishers = self._publishers(topic)
            named = self._names.get(topic) not in (None, NOT_YET_NAMED)
            if gid in publishers:
                self._unseen_since.pop(topic, None)
                gone = False
            elif named:                          # seen in the graph once, now gone
                gone = True
            else:                                # not discovered yet, or gone before it was
                since = self._unseen_since.setdefault(topic, time.monotonic())
                gone = time.monotonic() - since >= NEVER_SEEN_S
            if gone:
                self._unseen_since.pop(topic, None)
                self._report(only=topic)         # what it refused while it owned it
                inbox.release(topic)
                log.info(f"{topic}: its owner {self._names.pop(topic, NOT_YET_NAMED)} has "
                         "left; the next publisher's command takes it (command_owner first)")
            elif not named and gid in publishers:
                self._names[topic] = publishers[gid]
                if publishers[gid] != NOT_YET_NAMED:
                    log.info(f"{topic}: taking only {publishers[gid]}'s commands "
                             "(command_owner first)")
        return tuple((t, self._names.get(t, NOT_YET_NAMED)) for t in inbox.owners)
