"""The hand-compiled CDR encoders against rclpy's serializer: same length, same bytes except
alignment padding (which Fast CDR leaves uninitialised), and rclpy reads back the same message."""

from __future__ import annotations

import pytest
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64, String

from drill_sim.wire import cdr

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
