"""Messages a recorder never received, found from the publishers' own sequence numbers.

DDS numbers each message a writer sends (1, 2, 3, ... per publisher) and hands the number to
the reader with the message; with one publisher on a topic, a jump from n to n + k + 1 is
exactly k messages that publisher sent and this reader never got (ROS 2 raises no event for a
reliable history that overflows). With several publishers the numbers interleave and cannot be
told apart without the writer's id, which rclpy does not give: such topics are named as not
counted. The gaps go into the bag's ``recording`` metadata record, which ``drill_sim bag info``
shows for any bag afterwards.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Gap:
    """``count`` messages lost on ``topic`` between the ones received at ``after_s`` and
    ``before_s`` [s of the recording]."""

    topic: str
    count: int
    after_s: float
    before_s: float

    def line(self) -> str:
        return (f"lost {self.count} on {self.topic} between t = {self.after_s:.3f} and "
                f"{self.before_s:.3f} s of the recording")


@dataclass
class SequenceGaps:
    """Per topic, the last sequence number received and the gaps since the start."""

    gaps: list[Gap] = field(default_factory=list)
    uncounted: set[str] = field(default_factory=set)      # topics with several publishers
    # the publisher's number of the first message taken per topic: above 1, the publisher sent
    # that many before (before the recorder subscribed, or lost: a recording cannot tell)
    first: dict[str, int] = field(default_factory=dict)
    _last: dict[str, tuple[int, float]] = field(default_factory=dict)

    def note(self, topic: str, sequence: int | None, t_s: float, publishers: int = 1) -> None:
        """A message of ``topic`` with its publisher's ``sequence`` number (None or 0: the
        middleware gives none), received at ``t_s`` [s]; ``publishers`` is only read when
        the numbers jump."""
        if not sequence:
            return
        last = self._last.get(topic)
        self._last[topic] = (sequence, t_s)
        if last is None:
            self.first.setdefault(topic, sequence)
        if last is None or sequence <= last[0] + 1:
            return                         # in order, or a new publisher starting again at 1
        if publishers != 1:
            self.uncounted.add(topic)
            return
        self.gaps.append(Gap(topic, sequence - last[0] - 1, last[1], t_s))

    def last_sequence(self, topic: str) -> int | None:
        last = self._last.get(topic)
        return None if last is None else last[0]

    @property
    def lost(self) -> int:
        return sum(g.count for g in self.gaps)

    def lost_by_topic(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for g in self.gaps:
            out[g.topic] = out.get(g.topic, 0) + g.count
        return out

    def record(self) -> dict[str, str]:
        """The bag's ``recording`` metadata record (every value a string, as MCAP keeps)."""
        return {"lost_messages": str(self.lost),
                "lost_by_topic": json.dumps(self.lost_by_topic(), sort_keys=True),
                "gaps": json.dumps([[g.topic, g.count, round(g.after_s, 6),
                                     round(g.before_s, 6)] for g in self.gaps]),
                "loss_not_counted_on": json.dumps(sorted(self.uncounted)),
                "first_sequence_by_topic": json.dumps(self.first, sort_keys=True),
                "counted_from": "the publishers' sequence numbers"}
