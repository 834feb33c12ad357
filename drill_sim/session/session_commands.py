"""``SessionCommands``: the commands into a ``RigSession``, as the node takes them.

Each command is recorded as it arrived (its bytes and stamp), offered to the lockstep rule,
and applied by the node's rules (``rules.apply_command``: its field, unit and limit); a command
for the top-drive mode the drive left less than ``IN_FLIGHT_S`` ago was in flight at the
switch and is dropped without a warning. The counts are what /diagnostics reports.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Any

from ..wire import WireError, cdr, cdr_decode, rig_topics
from . import rules

# a command for the top-drive mode the drive left this recently [s] was in flight at the switch
IN_FLIGHT_S = 0.5

_ENCODE_COMMAND = cdr.stamped_vectors(rig_topics.FRAME_TOP_DRIVE)   # the drive's commands


class SessionCommands:
    """The commands of ``session`` (a ``RigSession``: its rig, parameters, recorder, lockstep
    rule, clock and stamps): ``received`` (recorded or not), ``superseded`` (replaced
    within their tick), ``last_s`` (wall clock of the last accepted batch [s])."""

    def __init__(self, session: Any) -> None:          # the RigSession (no import: a circle)
        self.session = session
        self.received = 0
        self.superseded = 0
        self.last_s = session.clock()
        self._mode_left: tuple[str, float] | None = None    # top-drive mode left, wall time

    def command(self, topic: rig_topics.RigTopic, frame_id: str, six, data: bytes = b"",
                stamp: tuple[int, int] = (0, 0), *, internal: bool = False
                ) -> rules.Refusal | str | None:
        """A command as it arrived on ``topic`` (``six``: its six float64 or a JointCommand;
        ``data``, its bytes, recorded; ``stamp``, its header stamp (sec, nanosec)). Accepted
        (None), it is held from now on; refused, the refusal (what, value, expected), or
        "in flight" for a command of the drive mode the rig left less than IN_FLIGHT_S ago
        (sent before the switch: dropped without a warning). ``internal``: the session's own
        scenario's set-point, which no lockstep tick waits for."""
        s = self.session
        self.received += 1
        if s.recorder is not None:
            s.recorder.record_command(topic, data, *stamp)
        if s.lockstep is not None and not internal:
            s.lockstep.offer(topic.name, stamp[0] * 1_000_000_000 + stamp[1])
        refusal = rules.apply_command(s.rig, s.p, topic.command, frame_id, six)
        if refusal is None:
            return None
        return "in flight" if self._in_flight(topic) else refusal

    def send(self, topic: rig_topics.RigTopic, six: Sequence[float], *,
             internal: bool = False) -> rules.Refusal | str | None:
        """A command the session's own driver makes (a scenario's set-point, the offline loop's
        law), stamped now: recorded as the message a driver would have sent (its bytes, only
        when recording), then ``command``."""
        sec, nsec = divmod(self.session.stamp_ns(), 1_000_000_000)
        data = _ENCODE_COMMAND(sec, nsec, six) if self.session.recorder is not None else b""
        return self.command(topic, rig_topics.FRAME_TOP_DRIVE, six, data, (sec, nsec),
                            internal=internal)

    def receive(self, topic: rig_topics.RigTopic, data: bytes) -> rules.Refusal | str | None:
        """A command message's CDR bytes as they arrived on ``topic``: decoded, then
        ``command``. Bytes that do not decode are refused as such (and not recorded)."""
        try:
            frame_id, sec, nanosec, six = cdr_decode.decode_command(topic.type_name, data)
        except (WireError, struct.error) as exc:
            return f"{topic.name} message", f"{len(data)} bytes", f"a CDR message ({exc})"
        return self.command(topic, frame_id, six, data, (sec, nanosec))

    def taken(self, accepted: int, topics: int) -> None:
        """A tick's batch taken: ``accepted`` commands on ``topics`` distinct topics (the
        others in the tick were superseded within it)."""
        if accepted:
            self.last_s = self.session.clock()
            self.superseded += accepted - topics

    def mode_left(self, mode: object) -> None:
        """The drive left top-drive mode ``mode`` now (a run-time change)."""
        self._mode_left = (str(mode), self.session.clock())

    def _in_flight(self, topic: rig_topics.RigTopic) -> bool:
        left = self._mode_left
        if left is None or self.session.clock() - left[1] > IN_FLIGHT_S:
            return False
        rule = rules.COMMANDS.get(topic.command)
        return rule is not None and rule.mode == left[0]
