"""JointState commands decoded without ROS, checked against rclpy's serializer."""

from __future__ import annotations

import pytest

from drill_sim.wire import WireError
from drill_sim.wire.cdr_decode import JointCommand, decode_command, decode_joint_state


def test_joint_state_bytes_decode_as_rclpy_serializes_them():
    """The decoder against rclpy's own serializer (an independent encoder)."""
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import JointState

    msg = JointState(name=["top_drive", "hook"], velocity=[1.5, -2.0], effort=[3.0, 4.5])
    msg.header.frame_id = "abc"
    msg.header.stamp.sec, msg.header.stamp.nanosec = 12, 345
    frame, sec, nsec, cmd = decode_joint_state(serialize_message(msg))
    assert (frame, sec, nsec) == ("abc", 12, 345)
    assert cmd == JointCommand(("top_drive", "hook"), (), (1.5, -2.0), (3.0, 4.5))


def test_truncated_or_absurd_joint_states_are_wire_errors():
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import JointState

    data = serialize_message(JointState(name=["top_drive"], effort=[1.0]))
    assert decode_command("sensor_msgs/msg/JointState", data)[3].effort == (1.0,)
    for bad in (data[:58], data[:20], b"\x01\x00\x00\x00" + data[4:]):
        with pytest.raises(WireError):
            decode_joint_state(bad)
    huge = bytearray(data)
    huge[20:24] = (10**6).to_bytes(4, "little")          # a million names
    with pytest.raises(WireError):
        decode_joint_state(bytes(huge))
