"""The lockstep rule, without ROS: after publishing tick k the rig waits until a command stamped
with tick k's simulation time has come on each lockstep topic, takes it, and only then advances
to tick k+1. So the loop is closed at exactly one tick whatever the wall-clock timing, and two
runs of a deterministic controller give the same session.

Commands on a lockstep topic stamped with any other time (a late answer to an earlier tick, a
second answer, a controller's own clock) are taken like any command, in arrival order (checked,
held, recorded), but do not release the tick; they are counted. A wait longer than the timeout
is reported once per timeout (the node warns and publishes tick k again, so a controller that
starts or restarts late picks the loop up) and the rig keeps waiting: it never advances without
the controller. ``msg_docs/node.md``, "Lockstep".

The drive answers to the command of its mode: when ``top_drive_mode`` changes at run time
between speed and torque (a controller with ``manage_drive_mode`` handing the drive back to
its speed loop, or taking it), a lockstep on one of the drive's two command topics moves to
the other, and a tick already answered on the old one stays answered.
"""

from __future__ import annotations

from dataclasses import dataclass

# the drive's command topic in each of its modes
DRIVE_COMMAND_TOPICS = {"kinematic": "~/cmd/top_drive", "speed": "~/cmd/top_drive",
                        "torque": "~/cmd/top_drive_torque"}


@dataclass(frozen=True)
class LockstepStatus:
    """What /diagnostics says about the wait: how long tick ``stamp_ns`` has waited [s], for
    which topics, the timeout [s], and the commands since start whose stamp was not the tick's."""

    waiting_s: float
    missing: tuple[str, ...]
    stamp_ns: int
    timeout_s: float
    other_stamps: int


class Lockstep:
    """Which commands the published tick still waits for.

    topics: the lockstep topics (names as in the topics table, ``~/cmd/...``); timeout_s: how
    long a wait may last [s] before it is reported."""

    def __init__(self, topics: tuple[str, ...], timeout_s: float) -> None:
        self.topics = tuple(topics)
        self.timeout_s = timeout_s
        self.stamp_ns: int | None = None          # the tick waited for; None: none published
        self.missing: set[str] = set()
        self.other_stamps = 0
        self._since = self._reported = 0.0

    def wait_for(self, stamp_ns: int, now_s: float) -> None:
        """Tick ``stamp_ns`` [ns] was published at wall time ``now_s`` [s]: wait for it."""
        self.stamp_ns, self.missing = stamp_ns, set(self.topics)
        self._since = self._reported = now_s

    def offer(self, topic: str, stamp_ns: int) -> bool:
        """A command on ``topic`` stamped ``stamp_ns`` [ns] was taken: True if it answers the
        tick waited for. Commands on other topics are no concern of the lockstep."""
        if topic not in self.topics:
            return False
        if stamp_ns == self.stamp_ns and topic in self.missing:
            self.missing.discard(topic)
            return True
        self.other_stamps += 1
        return False

    def follow_drive_mode(self, mode: str) -> str | None:
        """The drive is now in ``mode`` (speed or torque): wait on that mode's command topic
        instead of the other one's (when exactly one of the two is a lockstep topic); the
        topic now waited on, None if nothing moved."""
        to = DRIVE_COMMAND_TOPICS.get(mode)
        drive = [t for t in self.topics if t in DRIVE_COMMAND_TOPICS.values()]
        if to is None or len(drive) != 1 or drive[0] == to:
            return None
        self.topics = tuple(to if t == drive[0] else t for t in self.topics)
        if drive[0] in self.missing:
            self.missing.discard(drive[0])
            self.missing.add(to)
        return to

    @property
    def complete(self) -> bool:
        """Every lockstep topic answered the tick: the rig may advance."""
        return self.stamp_ns is not None and not self.missing

    def overdue(self, now_s: float) -> bool:
        """True once per ``timeout_s`` [s] of waiting for the same tick."""
        if self.stamp_ns is None or not self.missing or now_s - self._reported < self.timeout_s:
            return False
        self._reported = now_s
        return True

    def until_overdue(self, now_s: float) -> float:
        """Wall time left before the wait is next reported [s] (0 if due)."""
        return max(0.0, self._reported + self.timeout_s - now_s)

    def status(self, now_s: float) -> LockstepStatus:
        waiting = now_s - self._since if self.stamp_ns is not None and self.missing else 0.0
        return LockstepStatus(waiting, tuple(t for t in self.topics if t in self.missing),
                              self.stamp_ns or 0, self.timeout_s, self.other_stamps)
