"""Run as a script by tests: publish COUNT top-drive and COUNT hook-load commands to the rig
node RIG as fast as one process can (pre-serialized, reliable, the table's QoS), then exit."""

from __future__ import annotations

import sys
import time

import rclpy
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message


def main(rig: str, count: int) -> None:
    rclpy.init()
    node = rclpy.create_node("flood_commands")
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    speed = node.create_publisher(TwistStamped, f"{rig}/cmd/top_drive", qos)
    hook = node.create_publisher(WrenchStamped, f"{rig}/cmd/hook_load", qos)
    while not (speed.get_subscription_count() and hook.get_subscription_count()):
        time.sleep(0.01)
    s, h = TwistStamped(), WrenchStamped()
    s.header.frame_id = h.header.frame_id = "top_drive"
    s.twist.angular.z, h.wrench.force.z = 3.0, 238e3
    raw_speed, raw_hook = serialize_message(s), serialize_message(h)
    start = time.monotonic()
    for _ in range(count):
        speed.publish(raw_speed)
        hook.publish(raw_hook)
    print(f"published {2 * count} commands in {time.monotonic() - start:.2f} s", flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]))
