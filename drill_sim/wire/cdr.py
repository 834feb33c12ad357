"""Little-endian CDR encoders for the fixed-layout messages the rig uses, without ROS (their
decoders: ``cdr_decode``).

A message whose strings are fixed (frame ids, joint names) and whose arrays have a fixed length
has a fixed byte layout: a template holding every constant byte, into which the variable fields
are packed at known offsets. That takes about a microsecond, where rclpy's
``serialize_message`` takes 10-20 us, so the node publishes these bytes and records the very
same bytes. The output equals ``serialize_message``'s byte for byte, except that alignment
padding is zero here (Fast CDR leaves it uninitialised).

``layout`` gives a type's template with the offset of each field by its path in the message
(``wrench.force.z``, ``position[2]``, ``data``); ``fields_encoder`` fills named fields from an
object's attributes, which is how the rig's topics table (``rig_topics``) becomes encoders.
Values that do not fit their field and bytes that do not hold the expected message raise
``WireError``.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from operator import attrgetter

from . import WireError

ENCAPSULATION = b"\x00\x01\x00\x00"      # CDR, little endian, no options

Encoder = Callable[..., bytes]

# The six float64 of the stamped vector messages, in their order in the message.
VECTOR_FIELDS = {
    "geometry_msgs/msg/WrenchStamped": ("wrench.force.x", "wrench.force.y", "wrench.force.z",
                                        "wrench.torque.x", "wrench.torque.y", "wrench.torque.z"),
    "geometry_msgs/msg/TwistStamped": ("twist.linear.x", "twist.linear.y", "twist.linear.z",
                                       "twist.angular.x", "twist.angular.y", "twist.angular.z"),
}
# std_msgs types holding one primitive ``data`` field: its struct code
PRIMITIVE_DATA = {
    "std_msgs/msg/Bool": "?", "std_msgs/msg/Int8": "b", "std_msgs/msg/UInt8": "B",
    "std_msgs/msg/Int16": "h", "std_msgs/msg/UInt16": "H", "std_msgs/msg/Int32": "i",
    "std_msgs/msg/UInt32": "I", "std_msgs/msg/Int64": "q", "std_msgs/msg/UInt64": "Q",
    "std_msgs/msg/Float32": "f", "std_msgs/msg/Float64": "d",
}
CLOCK = "rosgraph_msgs/msg/Clock"
JOINT_STATE = "sensor_msgs/msg/JointState"


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
        data = _utf8(text) + b"\x00"
        self.constant("I", len(data))
        self.buf.extend(data)

    def stamp(self) -> tuple[int, struct.Struct]:
        """builtin_interfaces/Time: int32 sec, uint32 nanosec."""
        self._align(4)
        offset = len(self.buf)
        self.buf.extend(bytes(8))
        return offset, _STAMP

    def finish(self, fixed_size: bool = False) -> bytearray:
        """The bytes; a type without strings or sequences (``fixed_size``) is padded to a
        multiple of 4 bytes, as rmw does; others get no end padding."""
        if fixed_size:
            self.buf.extend(bytes(-len(self.buf) % 4))
        return self.buf


_STAMP = struct.Struct("<iI")
_SIX = struct.Struct("<6d")
_U32 = struct.Struct("<I")


def _utf8(text: str) -> bytes:
    try:
        return text.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise WireError(f"string {text!r} is not valid UTF-8 text: {exc.reason}") from None


def _packing(what: str) -> WireError:
    return WireError(f"{what}: a value does not fit its field")


def stamped_vectors(frame_id: str) -> Encoder:
    """geometry_msgs WrenchStamped or TwistStamped (same layout):
    ``encode(sec, nanosec, (x, y, z, x, y, z))`` - force then torque, or linear then angular."""
    t = Template()
    at_stamp, stamp = t.stamp()
    t.string(frame_id)
    at_values, values = t.field("d", 6)
    buf = t.finish()

    def encode(sec: int, nanosec: int, six: Sequence[float]) -> bytes:
        try:
            stamp.pack_into(buf, at_stamp, sec, nanosec)
            values.pack_into(buf, at_values, *six)
        except struct.error:
            raise _packing(f"stamped vectors ({sec}, {nanosec}, {six})") from None
        return bytes(buf)
    return encode


def _fixed(fmt: str, what: str) -> Encoder:
    pack = struct.Struct(fmt).pack

    def encode(*values) -> bytes:
        try:
            return pack(ENCAPSULATION, *values)
        except struct.error:
            raise _packing(f"{what} {values}") from None
    return encode


def float64() -> Encoder:
    """std_msgs/Float64: ``encode(value)``."""
    return _fixed("<4sd", "std_msgs/Float64")


def boolean() -> Encoder:
    """std_msgs/Bool: ``encode(flag)`` (fixed-size types are padded to 8 bytes)."""
    return _fixed("<4s?3x", "std_msgs/Bool")


def clock() -> Encoder:
    """rosgraph_msgs/Clock: ``encode(sec, nanosec)``."""
    return _fixed("<4siI", "rosgraph_msgs/Clock")


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
        try:
            stamp.pack_into(buf, at_stamp, sec, nanosec)
            pack_p.pack_into(buf, at_p, *positions)
            pack_v.pack_into(buf, at_v, *velocities)
            pack_e.pack_into(buf, at_e, *efforts)
        except struct.error:
            raise _packing(f"joint_states with {len(names)} joints") from None
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


# ---- layouts: a type's template and where each field sits -------------------------------------
@dataclass
class Layout:
    """One message type's template: ``slots`` maps a field path to (offset, struct code);
    ``stamps`` are the offsets of its builtin_interfaces/Time fields."""

    type_name: str
    buf: bytearray
    slots: dict[str, tuple[int, str]] = field(default_factory=dict)
    stamps: list[int] = field(default_factory=list)


def layout(type_name: str, *, frame_id: str = "", names: Sequence[str] = ()) -> Layout:
    """The fixed layout of ``type_name`` with this header frame_id and, for JointState, these
    joint names (position, velocity and effort as long as the names)."""
    t = Template()
    slots: dict[str, tuple[int, str]] = {}
    stamps: list[int] = []
    fixed_size = False
    if type_name in VECTOR_FIELDS:
        stamps.append(t.stamp()[0])
        t.string(frame_id)
        at, _ = t.field("d", 6)
        slots.update((path, (at + 8 * i, "d")) for i, path in enumerate(VECTOR_FIELDS[type_name]))
    elif type_name in PRIMITIVE_DATA:
        code = PRIMITIVE_DATA[type_name]
        slots["data"] = (t.field(code)[0], code)
        fixed_size = True
    elif type_name == CLOCK:
        stamps.append(t.stamp()[0])
        fixed_size = True
    elif type_name == JOINT_STATE:
        stamps.append(t.stamp()[0])
        t.string(frame_id)
        t.constant("I", len(names))
        for name in names:
            t.string(name)
        for array in ("position", "velocity", "effort"):
            t.constant("I", len(names))
            at, _ = t.field("d", len(names))
            slots.update((f"{array}[{j}]", (at + 8 * j, "d")) for j in range(len(names)))
    else:
        raise WireError(f"no fixed CDR layout for {type_name}")
    return Layout(type_name, t.finish(fixed_size), slots, stamps)


def fields_encoder(lay: Layout, fills: Sequence[tuple[str, str]]) -> Callable[..., bytes]:
    """``encode(sec, nanosec, source) -> bytes``: each stamp of the layout gets (sec, nanosec)
    and each (message field path, attribute) of ``fills`` the attribute of ``source`` (a
    RigSample, say); fields not filled stay zero. Adjacent fields are packed in one call."""
    paths = [path for path, _ in fills]
    unknown = [p for p in paths if p not in lay.slots]
    if unknown or len(set(paths)) != len(paths):
        raise WireError(f"{lay.type_name}: fields {unknown or paths} are not (each once) among "
                        f"{', '.join(lay.slots) or 'none'}")
    runs: list[tuple[int, str, list[str]]] = []
    for offset, code, attr in sorted(lay.slots[path] + (attr,) for path, attr in fills):
        if runs and runs[-1][1] == code \
                and runs[-1][0] + struct.calcsize(code) * len(runs[-1][2]) == offset:
            runs[-1][2].append(attr)
        else:
            runs.append((offset, code, [attr]))
    singles = tuple((at, struct.Struct("<" + code).pack_into, attrgetter(attrs[0]))
                    for at, code, attrs in runs if len(attrs) == 1)
    multiples = tuple((at, struct.Struct(f"<{len(attrs)}{code}").pack_into, attrgetter(*attrs))
                      for at, code, attrs in runs if len(attrs) > 1)
    buf, stamps, pack_stamp = lay.buf, tuple(lay.stamps), _STAMP.pack_into

    def encode(sec: int, nanosec: int, source: object) -> bytes:
        try:
            for at in stamps:
                pack_stamp(buf, at, sec, nanosec)
            for at, pack, get in singles:
                pack(buf, at, get(source))
            for at, pack, get in multiples:
                pack(buf, at, *get(source))
        except struct.error:
            raise _packing(f"{lay.type_name} at stamp ({sec}, {nanosec})") from None
        return bytes(buf)
    return encode
