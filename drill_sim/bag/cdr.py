"""Little-endian CDR encoders for the fixed-layout messages the rig publishes, without ROS.

A message whose strings are fixed (frame ids, joint names) and whose arrays have a fixed length
has a fixed byte layout: a template holding every constant byte, into which the variable fields
are packed at known offsets. That takes about a microsecond, where rclpy's
``serialize_message`` takes 10-20 us, so the node publishes these bytes and records the very
same bytes. The output equals ``serialize_message``'s byte for byte, except that alignment
padding is zero here (Fast CDR leaves it uninitialised).
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence

ENCAPSULATION = b"\x00\x01\x00\x00"      # CDR, little endian, no options

Encoder = Callable[..., bytes]


class Template:
    """A message's bytes with its constant parts filled in; ``field`` reserves room for
    variable values and returns where they go. Alignment counts from after the encapsulation
    header, as CDR does."""

    def __init__(self) -> None:
        self.buf = bytearray(ENCAPSULATION)

    def _align(self, size: int) -> None:
        self.buf.extend(bytes(-(len(self.buf) - 4) % size))

    def field(self, code: str, count: int = 1) -> tuple[int, struct.Struct]:
        """Room for ``count`` values of struct code ``code``: (offset, packer)."""
        packer = struct.Struct(f"<{count}{code}")
        self._align(struct.calcsize("<" + code))
        offset = len(self.buf)
        self.buf.extend(bytes(packer.size))
        return offset, packer

    def constant(self, code: str, value: int) -> None:
        offset, packer = self.field(code)
        packer.pack_into(self.buf, offset, value)

    def string(self, text: str) -> None:
        data = text.encode("utf-8") + b"\x00"
        self.constant("I", len(data))
        self.buf.extend(data)

    def stamp(self) -> tuple[int, struct.Struct]:
        """builtin_interfaces/Time: int32 sec, uint32 nanosec."""
        self._align(4)
        offset = len(self.buf)
        self.buf.extend(bytes(8))
        return offset, _STAMP

    def finish(self) -> bytearray:
        return self.buf                    # no end padding for types with strings or sequences


_STAMP = struct.Struct("<iI")


def stamped_vectors(frame_id: str) -> Encoder:
    """geometry_msgs WrenchStamped or TwistStamped (same layout):
    ``encode(sec, nanosec, (x, y, z, x, y, z))`` - force then torque, or linear then angular."""
    t = Template()
    at_stamp, stamp = t.stamp()
    t.string(frame_id)
    at_values, values = t.field("d", 6)
    buf = t.finish()

    def encode(sec: int, nanosec: int, six: Sequence[float]) -> bytes:
        stamp.pack_into(buf, at_stamp, sec, nanosec)
        values.pack_into(buf, at_values, *six)
        return bytes(buf)
    return encode


def float64() -> Encoder:
    """std_msgs/Float64: ``encode(value)``."""
    pack = struct.Struct("<4sd").pack
    return lambda value: pack(ENCAPSULATION, value)


def boolean() -> Encoder:
    """std_msgs/Bool: ``encode(flag)`` (fixed-size types are padded to 8 bytes)."""
    pack = struct.Struct("<4s?3x").pack
    return lambda flag: pack(ENCAPSULATION, flag)


def clock() -> Encoder:
    """rosgraph_msgs/Clock: ``encode(sec, nanosec)``."""
    pack = struct.Struct("<4siI").pack
    return lambda sec, nanosec: pack(ENCAPSULATION, sec, nanosec)


def string(text: str) -> bytes:
    """std_msgs/String (any text; compiled per call, for rare messages)."""
    t = Template()
    t.string(text)
    return bytes(t.finish())


def joint_state(frame_id: str, names: Sequence[str]) -> Encoder:
    """sensor_msgs/JointState with fixed names and position, velocity and effort as long as
    the names: ``encode(sec, nanosec, positions, velocities, efforts)``."""
    t = Template()
    at_stamp, stamp = t.stamp()
    t.string(frame_id)
    t.constant("I", len(names))
    for name in names:
        t.string(name)
    arrays = []
    for _ in range(3):
        t.constant("I", len(names))
        arrays.append(t.field("d", len(names)))
    buf = t.finish()
    (at_p, pack_p), (at_v, pack_v), (at_e, pack_e) = arrays

    def encode(sec: int, nanosec: int, positions: Sequence[float],
               velocities: Sequence[float], efforts: Sequence[float]) -> bytes:
        stamp.pack_into(buf, at_stamp, sec, nanosec)
        pack_p.pack_into(buf, at_p, *positions)
        pack_v.pack_into(buf, at_v, *velocities)
        pack_e.pack_into(buf, at_e, *efforts)
        return bytes(buf)
    return encode


class StampedVectorsByFrame:
    """``stamped_vectors`` for messages arriving with any frame_id (the commands): one
    compiled encoder per frame seen, at most ``limit`` of them."""

    def __init__(self, limit: int = 64) -> None:
        self._encoders: dict[str, Encoder] = {}
        self._limit = limit

    def __call__(self, frame_id: str, sec: int, nanosec: int, six: Sequence[float]) -> bytes:
        enc = self._encoders.get(frame_id)
        if enc is None:
            if len(self._encoders) >= self._limit:
                self._encoders.clear()
            enc = self._encoders[frame_id] = stamped_vectors(frame_id)
        return enc(sec, nanosec, six)
