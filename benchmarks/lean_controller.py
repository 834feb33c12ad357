"""A lean closed-loop controller for a rig in lockstep, in its own process: the same PI on the
bit speed as ``tests/ros/lockstep_controller.py`` (same arguments, same output lines), but
written for speed, so that a lockstep benchmark measures the rig's cost rather than a client
library's. Plain rclpy and ``struct``, no drill_sim code: any controller may be written so.

Why it is cheaper: the sample arrives as CDR bytes (a raw subscription: no message object is
built) and only the stamp and ``twist.angular.z`` are read from it; the command is a
pre-encoded ``TwistStamped`` whose stamp and speed are patched in place and published as bytes
(no serialization), straight to the publisher's handle (``Publisher.publish`` adds ~10 us of
guard and type checks a call). The wait for a sample is one of --wait:

- ``waitset`` (default): an rcl wait set on the one subscription, then a raw take, no
  executor (each wait attaches and detaches Fast DDS's conditions, ~25 us of CPU here);
- ``events``: an EventsExecutor holding only this subscription calls back with the bytes
  (measured: 20-50 us more CPU a tick than the wait set).

``--best-effort`` subscribes and publishes best effort, to a rig started with
``qos_reliability:=best_effort`` (no acknowledgements, no heartbeats: less middleware work on
both sides; on one host nothing is lost at one sample a tick, and a lost one would make the
rig publish its tick again after ``lockstep_timeout_s``).

    python lean_controller.py --rig /rig1/drill_sim --ticks 5000 --resume [--wait events]
        [--best-effort]
"""

from __future__ import annotations

import argparse
import struct
import sys
import time

import rclpy
from geometry_msgs.msg import TwistStamped
from rclpy.executors import SingleThreadedExecutor
from rclpy.experimental import EventsExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.type_support import check_is_valid_msg_type
from std_srvs.srv import SetBool

CDR_LE = b"\x00\x01\x00\x00"       # encapsulation: plain CDR, little-endian
FRAME = b"top_drive"


def command_template() -> tuple[bytearray, int]:
    """A TwistStamped (frame ``top_drive``, all zero) as CDR bytes, and the offset of its
    ``twist.angular.z``; the stamp is at offset 4 (int32 sec, uint32 nanosec)."""
    head = CDR_LE + bytes(8) + struct.pack("<I", len(FRAME) + 1) + FRAME + b"\x00"
    pad = -(len(head) - 4) % 8                  # float64 aligned from the payload's start
    buf = bytearray(head + bytes(pad) + bytes(48))
    return buf, len(buf) - 8


def read_sample(data: bytes) -> tuple[bytes, float]:
    """(the stamp's 8 bytes, ``twist.angular.z``) of a little-endian TwistStamped."""
    if data[:4] != CDR_LE:
        raise ValueError("not little-endian CDR")
    (n,) = struct.unpack_from("<I", data, 12)
    off = 16 + n
    off += -(off - 4) % 8
    return data[4:12], struct.unpack_from("<d", data, off + 40)[0]


class LeanPI:
    """The PI of ``lockstep_controller.BitSpeedPI`` on raw bytes: speed = reference + kp e +
    ki * integral of e over the stamps' simulated time, clamped to [0, max] rad/s."""

    def __init__(self, args: argparse.Namespace, publish) -> None:
        self.args, self.publish = args, publish
        self.answered = 0
        self.integral = 0.0
        self.last_s: float | None = None
        self.last_stamp = b""
        self.first_wall = self.last_wall = 0.0
        self.cmd, self.speed_at = command_template()
        self.last_cmd = bytes(self.cmd)

    def on_sample(self, data: bytes) -> None:
        a = self.args
        if a.ticks and self.answered >= a.ticks:
            return
        stamp, bit_speed = read_sample(data)
        if stamp == self.last_stamp:                          # the same tick published again
            self.publish(self.last_cmd)
            return
        self.last_stamp = stamp
        sec, nsec = struct.unpack("<iI", stamp)
        t = sec + 1e-9 * nsec
        if a.step_at_s is not None:
            speed = a.step_to if t >= a.step_at_s - 1e-12 else a.hold_speed
        else:
            error = a.reference - bit_speed
            if self.last_s is not None:
                self.integral += error * (t - self.last_s)
            self.last_s = t
            speed = a.reference + a.kp * error + a.ki * self.integral
        cmd = self.cmd
        cmd[4:12] = stamp                                     # the tick this answers
        struct.pack_into("<d", cmd, self.speed_at, min(max(speed, 0.0), a.max_speed))
        self.last_cmd = bytes(cmd)
        self.publish(self.last_cmd)
        self.last_wall = time.monotonic()
        if not self.answered:
            self.first_wall = self.last_wall
        self.answered += 1


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rig", default="/drill_sim", help="the rig node's full name")
    parser.add_argument("--ticks", type=int, default=0, help="samples to answer; 0: for ever")
    parser.add_argument("--reference", type=float, default=8.0, help="bit speed [rad/s]")
    parser.add_argument("--kp", type=float, default=0.5, help="[1]")
    parser.add_argument("--ki", type=float, default=0.5, help="[1/s]")
    parser.add_argument("--max-speed", type=float, default=25.0, help="[rad/s]")
    parser.add_argument("--step-at-s", type=float, default=None, help="sample stamp [s]")
    parser.add_argument("--step-to", type=float, default=10.0, help="[rad/s]")
    parser.add_argument("--hold-speed", type=float, default=6.283185307179586, help="[rad/s]")
    parser.add_argument("--resume", action="store_true")
    parser.add_argument("--wait", choices=("events", "waitset"), default="waitset")
    parser.add_argument("--best-effort", action="store_true",
                        help="best-effort QoS (the rig's qos_reliability:=best_effort)")
    args = parser.parse_args()
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT if args.best_effort
                     else ReliabilityPolicy.RELIABLE)
    rclpy.init()
    node = rclpy.create_node("lean_controller")
    pub = node.create_publisher(TwistStamped, f"{args.rig}/cmd/top_drive", qos)
    pi = LeanPI(args, pub.handle.publish_raw)   # bytes, without Publisher.publish's ~10 us
    topic = f"{args.rig}/bit/twist"
    if args.wait == "events":
        sub = node.create_subscription(TwistStamped, topic, pi.on_sample, qos, raw=True)
        count_publishers = sub.get_publisher_count
    else:                              # outside any executor: only this loop takes from it
        check_is_valid_msg_type(TwistStamped)
        with node.handle:
            sub = _rclpy.Subscription(node.handle, TwistStamped, topic,
                                      qos.get_c_qos_profile())
        count_publishers = sub.get_publisher_count
    setup = SingleThreadedExecutor()   # matching and the resume call; no samples flow yet
    setup.add_node(node)
    try:
        while pub.get_subscription_count() == 0 or count_publishers() == 0:
            setup.spin_once(timeout_sec=0.01)
        if args.resume:
            client = node.create_client(SetBool, f"{args.rig}/pause")
            while not client.service_is_ready():
                setup.spin_once(timeout_sec=0.01)
            future = client.call_async(SetBool.Request(data=False))
            while not future.done():
                setup.spin_once(timeout_sec=0.01)
        setup.remove_node(node)
        print("connected", flush=True)
        if args.wait == "events":
            loop = EventsExecutor()
            loop.add_node(node)
            while not args.ticks or pi.answered < args.ticks:
                loop.spin_once(timeout_sec=0.1)
            loop.shutdown()
        else:
            wait_loop(node, sub, pi, args.ticks)
        print(f"answered {pi.answered} in {pi.last_wall - pi.first_wall:.6f} s", flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        setup.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


def wait_loop(node, sub, pi: LeanPI, ticks: int) -> None:
    """Wait on the one subscription, take what came (raw bytes), answer; no executor."""
    context = node.context.handle
    ws = _rclpy.WaitSet(1, 0, 0, 0, 0, 0, context)
    while not ticks or pi.answered < ticks:
        taken = sub.take_message(TwistStamped, True)
        if taken is None:
            with context:
                ws.clear_entities()
                ws.add_subscription(sub)
                ws.wait(100_000_000)
            continue
        pi.on_sample(taken[0])
    ws.destroy_when_not_in_use()
    sub.destroy_when_not_in_use()


if __name__ == "__main__":
    sys.exit(main())
