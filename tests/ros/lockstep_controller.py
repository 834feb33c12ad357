"""A closed-loop controller for a rig in lockstep, in its own process: plain rclpy, no drill_sim
client code. A PI on the bit speed (``~/bit/twist``, ``twist.angular.z`` [rad/s]) sets the
top-drive speed (``~/cmd/top_drive``); each command carries the stamp of the sample it answers,
which is all lockstep asks of a controller.

    python lockstep_controller.py --rig /rig1/drill_sim --ticks 2000 [--resume]

--resume: once connected both ways, resume a rig started with ``start_paused:=true``.
--step-at-s T --step-to X: instead of the PI, command --hold-speed, and X [rad/s] from the
sample stamped T [s] on (to see exactly when a command lands). --ticks 0: answer for ever.
A sample published again (same stamp) gets the same command again and is not counted.
Prints ``answered N in S s`` when done (S: wall time from the first answer to the last; it
then stops answering, so the rig waits).
"""

from __future__ import annotations

import argparse
import signal
import sys
import time

import rclpy
from geometry_msgs.msg import TwistStamped
from rclpy.executors import SingleThreadedExecutor
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from std_srvs.srv import SetBool


class BitSpeedPI(Node):
    """Top-drive speed = reference + kp e + ki * integral of e, e = reference - bit speed,
    over the sample stamps' simulated time; clamped to [0, max] rad/s."""

    def __init__(self, args: argparse.Namespace) -> None:
        super().__init__("lockstep_controller")
        self.args = args
        self.answered = 0
        self.done = False                # answered --ticks samples and saw the rig move on
        self.integral = 0.0
        self.last_s: float | None = None
        self.last_stamp: tuple[int, int] | None = None
        self.first_wall = self.last_wall = 0.0
        self.pub = self.create_publisher(TwistStamped, f"{args.rig}/cmd/top_drive", 10)
        self.sub = self.create_subscription(TwistStamped, f"{args.rig}/bit/twist",
                                            self.on_sample, 10)
        self.cmd = TwistStamped()
        self.cmd.header.frame_id = "top_drive"

    def on_sample(self, sample: TwistStamped) -> None:
        a = self.args
        if a.ticks and self.answered >= a.ticks:
            # the rig took the last answer once it publishes the next tick: only then is the
            # session's end the same in every run (stopping the rig before could lose that tick)
            self.done = self.done or (sample.header.stamp.sec, sample.header.stamp.nanosec) \
                != self.last_stamp
            return
        stamp = (sample.header.stamp.sec, sample.header.stamp.nanosec)
        if stamp == self.last_stamp:                          # the same tick published again
            self.pub.publish(self.cmd)
            return
        self.last_stamp = stamp
        t = stamp[0] + 1e-9 * stamp[1]
        if a.step_at_s is not None:
            speed = a.step_to if t >= a.step_at_s - 1e-12 else a.hold_speed
        else:
            error = a.reference - sample.twist.angular.z
            if self.last_s is not None:
                self.integral += error * (t - self.last_s)
            self.last_s = t
            speed = a.reference + a.kp * error + a.ki * self.integral
        self.cmd.header.stamp = sample.header.stamp           # the tick this answers
        self.cmd.twist.angular.z = min(max(speed, 0.0), a.max_speed)
        self.pub.publish(self.cmd)
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
    parser.add_argument("--executor", choices=("events", "single"), default="events")
    args = parser.parse_args()
    # Ctrl-C and SIGTERM only raise a flag, looked at between spins: neither rclpy shutting
    # the context down under a callback that is publishing, nor a KeyboardInterrupt inside
    # the executor's C++ (which surfaced as a RuntimeError): the controller stops cleanly
    # and says what it did
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    stop: list[int] = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda signum, frame: stop.append(signum))
    node = BitSpeedPI(args)
    executor = EventsExecutor() if args.executor == "events" else SingleThreadedExecutor()
    executor.add_node(node)

    def spin_until(done, timeout_s: float = 0.01) -> bool:
        while not stop and not done():
            executor.spin_once(timeout_sec=timeout_s)
        return not stop

    def connected() -> bool:
        if node.pub.get_subscription_count() > 0 and node.sub.get_publisher_count() > 0:
            return True
        if not said and time.monotonic() > waiting_since + 5.0:     # a wrong --rig, say
            said.append(True)
            print(f"waiting for the rig {args.rig} (nothing publishes {node.sub.topic_name} "
                  "yet; is --rig the rig node's full name?)", flush=True)
        return False

    waiting_since, said = time.monotonic(), []
    try:
        if not spin_until(connected):
            return 0
        if args.resume:
            client = node.create_client(SetBool, f"{args.rig}/pause")
            if not spin_until(client.service_is_ready):
                return 0
            future = client.call_async(SetBool.Request(data=False))
            if not spin_until(future.done):
                return 0
        print("connected", flush=True)
        spin_until(lambda: bool(args.ticks) and node.done, 0.1)
    finally:
        print(f"answered {node.answered} in {node.last_wall - node.first_wall:.6f} s",
              flush=True)
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
