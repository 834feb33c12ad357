"""Little-endian CDR decoders for the messages the rig takes and the tools read, without ROS:
the drive's commands (TwistStamped, WrenchStamped, a JointState of joint commands) and the
diagnostics array. Bytes that do not hold the expected message raise ``WireError``; counts are
bounded (``MAX_JOINT_COMMAND_NAMES``, ``MAX_DIAGNOSTIC_ENTRIES``) so a corrupt length never
allocates without bound."""

from __future__ import annotations

import struct
from typing import NamedTuple

from . import WireError
from .cdr import _SIX, _STAMP, _U32, ENCAPSULATION, JOINT_STATE


def decode_stamped_vectors(data: bytes) -> tuple[str, int, int, tuple[float, ...]]:
    """frame_id, stamp (sec, nanosec) and the six float64 (VECTOR_FIELDS order) of a
    TwistStamped or WrenchStamped in little-endian CDR."""
    try:
        if bytes(data[:2]) != ENCAPSULATION[:2]:
            raise WireError(f"not little-endian CDR (header {bytes(data[:4]).hex()})")
        sec, nanosec = _STAMP.unpack_from(data, 4)
        (n,) = _U32.unpack_from(data, 12)
        if n < 1:
            raise WireError("frame_id of length 0 (no terminating NUL)")
        frame = bytes(data[16:16 + n - 1]).decode("utf-8", "replace")
        at = 16 + n
        at += -(at - 4) % 8
        six = _SIX.unpack_from(data, at)
    except struct.error:
        raise WireError(f"{len(data)} bytes cannot hold a stamped vector message") from None
    return frame, sec, nanosec, six


class JointCommand(NamedTuple):
    """A sensor_msgs/JointState taken as a command: joint names and the three arrays (each
    empty or, when well formed, as long as the names)."""

    name: tuple[str, ...]
    position: tuple[float, ...]
    velocity: tuple[float, ...]
    effort: tuple[float, ...]


class _Reader:
    """Reads CDR fields in order, aligned from after the encapsulation header."""

    def __init__(self, data: bytes, at: int) -> None:
        self.data, self.at = data, at

    def _align(self, size: int) -> None:
        self.at += -(self.at - 4) % size

    def u32(self) -> int:
        self._align(4)
        (n,) = _U32.unpack_from(self.data, self.at)
        self.at += 4
        return n

    def string(self) -> str:
        n = self.u32()
        if n < 1 or self.at + n > len(self.data):
            raise WireError(f"a string of length {n} (no terminating NUL, or past the end)")
        text = bytes(self.data[self.at:self.at + n - 1]).decode("utf-8", "replace")
        self.at += n
        return text

    def doubles(self) -> tuple[float, ...]:
        n = self.u32()
        if n == 0:
            return ()
        self._align(8)
        values = struct.unpack_from(f"<{n}d", self.data, self.at)
        self.at += 8 * n
        return values


MAX_JOINT_COMMAND_NAMES = 64              # a command names a few joints; more is not one


def decode_joint_state(data: bytes) -> tuple[str, int, int, JointCommand]:
    """frame_id, stamp (sec, nanosec) and the names and arrays of a sensor_msgs/JointState in
    little-endian CDR (any lengths; ``JointCommand`` says which are well formed)."""
    try:
        if bytes(data[:2]) != ENCAPSULATION[:2]:
            raise WireError(f"not little-endian CDR (header {bytes(data[:4]).hex()})")
        sec, nanosec = _STAMP.unpack_from(data, 4)
        r = _Reader(data, 12)
        frame = r.string()
        count = r.u32()
        if count > MAX_JOINT_COMMAND_NAMES:
            raise WireError(f"{count} joint names (at most {MAX_JOINT_COMMAND_NAMES})")
        names = tuple(r.string() for _ in range(count))
        position, velocity, effort = r.doubles(), r.doubles(), r.doubles()
    except struct.error:
        raise WireError(f"{len(data)} bytes cannot hold a JointState") from None
    return frame, sec, nanosec, JointCommand(names, position, velocity, effort)


class DiagnosticStatusRecord(NamedTuple):
    """One diagnostic_msgs/DiagnosticStatus as decoded: level 0 OK, 1 WARN, 2 ERROR, 3 STALE."""

    level: int
    name: str
    message: str
    hardware_id: str
    values: tuple[tuple[str, str], ...]    # (key, value) in message order


MAX_DIAGNOSTIC_ENTRIES = 4096             # statuses in an array, or values in a status


def decode_diagnostic_array(data: bytes) -> tuple[int, int, tuple[DiagnosticStatusRecord, ...]]:
    """Stamp (sec, nanosec) and the statuses of a diagnostic_msgs/DiagnosticArray in
    little-endian CDR."""
    try:
        if bytes(data[:2]) != ENCAPSULATION[:2]:
            raise WireError(f"not little-endian CDR (header {bytes(data[:4]).hex()})")
        sec, nanosec = _STAMP.unpack_from(data, 4)
        r = _Reader(data, 12)
        r.string()                                             # frame_id
        statuses = []
        for _ in range(_count(r.u32(), "statuses")):
            level = data[r.at]
            r.at += 1
            name, message, hardware_id = r.string(), r.string(), r.string()
            values = tuple((r.string(), r.string())
                           for _ in range(_count(r.u32(), "values")))
            statuses.append(DiagnosticStatusRecord(level, name, message, hardware_id, values))
    except (struct.error, IndexError):
        raise WireError(f"{len(data)} bytes cannot hold this DiagnosticArray") from None
    return sec, nanosec, tuple(statuses)


def _count(n: int, what: str) -> int:
    if n > MAX_DIAGNOSTIC_ENTRIES:
        raise WireError(f"{n} {what} (at most {MAX_DIAGNOSTIC_ENTRIES}): not a DiagnosticArray")
    return n


def decode_command(type_name: str, data: bytes
                   ) -> tuple[str, int, int, tuple[float, ...] | JointCommand]:
    """A command message's frame_id, stamp and values: the six float64 of a TwistStamped or
    WrenchStamped (``decode_stamped_vectors``), or a JointState's ``JointCommand``."""
    return command_decoder(type_name)(data)


def command_decoder(type_name: str):
    """The decoder ``decode_command`` uses for messages of ``type_name`` (chosen once, for a
    subscription that decodes every message it takes)."""
    return decode_joint_state if type_name == JOINT_STATE else decode_stamped_vectors
