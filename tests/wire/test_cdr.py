"""The hand-compiled CDR encoders against rclpy's serializer: same length, same bytes except
alignment padding (which Fast CDR leaves uninitialised), and rclpy reads back the same message."""

from __future__ import annotations

import pytest
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64, String

from drill_sim.wire import cdr, cdr_decode

VALUES = [(0.0, -0.0, 1.5, -3.25e7, 1e-300, 123.456), (1.0, 2.0, 3.0, 4.0, 5.0, 6.0)]


def _same(ours: bytes, msg) -> None:
    theirs = serialize_message(msg)
    assert len(ours) == len(theirs)
    assert all(a == b or a == 0 for a, b in zip(ours, theirs, strict=True))
    assert deserialize_message(ours, type(msg)) == msg


@pytest.mark.parametrize("frame", ["", "bit", "top_drive", "a_frame_of_odd_length", "é"])
@pytest.mark.parametrize("six", VALUES)
def test_stamped_vectors_match_rclpy(frame, six):
    w = WrenchStamped()
    w.header.frame_id = frame
    w.header.stamp.sec, w.header.stamp.nanosec = 1_700_000_123, 999_999_999
    (w.wrench.force.x, w.wrench.force.y, w.wrench.force.z,
     w.wrench.torque.x, w.wrench.torque.y, w.wrench.torque.z) = six
    encode = cdr.stamped_vectors(frame)
    _same(encode(1_700_000_123, 999_999_999, six), w)
    t = TwistStamped()
    t.header = w.header
    (t.twist.linear.x, t.twist.linear.y, t.twist.linear.z,
     t.twist.angular.x, t.twist.angular.y, t.twist.angular.z) = six
    _same(cdr.StampedVectorsByFrame()(frame, 1_700_000_123, 999_999_999, six), t)


@pytest.mark.parametrize("names", [("top_drive", "hook", "bit_rotation", "bit_axial"), ("a",),
                                   ("ab", "abc", "abcd", "abcde", "x")])
def test_joint_state_matches_rclpy(names):
    n = len(names)
    j = JointState(name=list(names), position=[0.5 * i for i in range(n)],
                   velocity=[-1.0 * i for i in range(n)], effort=[1e6 + i for i in range(n)])
    j.header.frame_id = "bit"
    j.header.stamp.sec = 42
    _same(cdr.joint_state("bit", names)(42, 0, j.position, j.velocity, j.effort), j)


@pytest.mark.parametrize("text", ["", "a", "abcd", '{"event": "reset"}', "grad °"])
def test_string_matches_rclpy(text):
    _same(cdr.string(text), String(data=text))


def test_scalars_match_rclpy():
    for flag in (True, False):
        _same(cdr.boolean()(flag), Bool(data=flag))
    for value in (0.0, -2.5, 1e300):
        _same(cdr.float64()(value), Float64(data=value))
    c = Clock()
    c.clock.sec, c.clock.nanosec = 12, 345
    _same(cdr.clock()(12, 345), c)


@pytest.mark.parametrize("type_name", sorted(cdr.PRIMITIVE_DATA))
def test_layout_of_primitive_data_types_matches_rclpy(type_name):
    import importlib
    from types import SimpleNamespace
    cls = getattr(importlib.import_module("std_msgs.msg"), type_name.rsplit("/", 1)[1])
    code = cdr.PRIMITIVE_DATA[type_name]
    value = {"?": True, "f": 1.5, "d": -2.25}.get(code, 7)
    encode = cdr.fields_encoder(cdr.layout(type_name), [("data", "value")])
    _same(encode(0, 0, SimpleNamespace(value=value)), cls(data=value))


def test_fields_encoder_fills_named_fields_and_leaves_the_rest_zero():
    from types import SimpleNamespace
    src = SimpleNamespace(a=1.5, b=-2.0, c=3.25)
    lay = cdr.layout("geometry_msgs/msg/WrenchStamped", frame_id="bit")
    encode = cdr.fields_encoder(lay, [("wrench.force.z", "a"), ("wrench.torque.x", "b"),
                                      ("wrench.torque.y", "c")])
    w = WrenchStamped()
    w.header.frame_id = "bit"
    w.header.stamp.sec, w.header.stamp.nanosec = 3, 4
    w.wrench.force.z, w.wrench.torque.x, w.wrench.torque.y = 1.5, -2.0, 3.25
    _same(encode(3, 4, src), w)
    names = ("j0", "joint_1", "j2")
    lay = cdr.layout("sensor_msgs/msg/JointState", names=names)
    encode = cdr.fields_encoder(lay, [("position[0]", "a"), ("position[1]", "b"),
                                      ("effort[2]", "c")])
    j = JointState(name=list(names), position=[1.5, -2.0, 0.0], velocity=[0.0] * 3,
                   effort=[0.0, 0.0, 3.25])
    j.header.stamp.sec = 9
    _same(encode(9, 0, src), j)


def test_wire_errors_name_what_does_not_fit():
    from types import SimpleNamespace

    from drill_sim.wire import WireError
    with pytest.raises(WireError, match="no fixed CDR layout"):
        cdr.layout("std_msgs/msg/String")
    lay = cdr.layout("std_msgs/msg/Float64")
    with pytest.raises(WireError, match="not"):
        cdr.fields_encoder(lay, [("value", "a")])
    with pytest.raises(WireError, match="does not fit"):
        cdr.fields_encoder(lay, [("data", "a")])(0, 0, SimpleNamespace(a="text"))
    with pytest.raises(WireError, match="does not fit"):
        cdr.clock()(2**31, 0)                        # sec is an int32
    with pytest.raises(WireError, match="UTF-8"):
        cdr.string("\ud800")
    with pytest.raises(WireError, match="cannot hold"):
        cdr_decode.decode_stamped_vectors(cdr.stamped_vectors("top_drive")(1, 2, VALUES[1])[:30])


@pytest.mark.parametrize("frame", ["", "top_drive", "é"])
def test_decode_stamped_vectors_reads_what_rclpy_writes(frame):
    t = TwistStamped()
    t.header.frame_id = frame
    t.header.stamp.sec, t.header.stamp.nanosec = -5, 7
    (t.twist.linear.x, t.twist.linear.y, t.twist.linear.z,
     t.twist.angular.x, t.twist.angular.y, t.twist.angular.z) = VALUES[0]
    assert cdr_decode.decode_stamped_vectors(serialize_message(t)) == (frame, -5, 7, VALUES[0])
