"""The rig node under a flood of commands [issue target: outputs keep their rate, max gap
between consecutive outputs < 20 ms of wall time].

A rig node (1000 Hz, real time) runs in one process; another process publishes --count
top-drive and --count hook-load commands as fast as it can (reliable, the table's QoS); this
process receives ``~/joint_states`` and ``/diagnostics`` (raw, nothing else to do) and prints
the gaps between consecutive joint_states arrivals during the flood, the diagnostics received,
the node's command counters, and whether a command sent after the flood was applied.

Run: .venv/bin/python benchmarks/bench_flood.py [--count 100000] [--record]
The flood is published by tests/ros/flood_commands.py, the flooder the node's flood test uses.
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState

BIN = Path(sys.executable).parent
NS = "/flood"
RIG = f"{NS}/drill_sim"
# the flooder the tests use: both topics, pre-serialized, as fast as one process goes
FLOODER = Path(__file__).resolve().parents[1] / "tests" / "ros" / "flood_commands.py"
QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--count", type=int, default=100_000, help="commands per topic")
    parser.add_argument("--record", action="store_true", help="the node records its session")
    args = parser.parse_args()
    os.environ.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    tmp = tempfile.TemporaryDirectory()
    record = ("-p", f"record:={tmp.name}/bag") if args.record else ()
    node_proc = subprocess.Popen([str(BIN / "drill_sim_node"), "--ros-args", "-r",
                                  f"__ns:={NS}", "-p", "command_timeout_s:=100.0", *record],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    rclpy.init()
    node = rclpy.create_node("drill_sim_bench_flood")
    arrivals: list[float] = []
    diagnostics: list[tuple[float, dict[str, str]]] = []
    speeds: list[float] = []
    node.create_subscription(JointState, f"{RIG}/joint_states", lambda m: (
        arrivals.append(time.monotonic()), speeds.append(m.velocity[0])), 1000)
    node.create_subscription(DiagnosticArray, "/diagnostics", lambda m: diagnostics.extend(
        (time.monotonic(), {kv.key: kv.value for kv in s.values}) for s in m.status
        if s.hardware_id and s.name.startswith("drill_sim")), 100)
    while len(arrivals) < 2000:
        rclpy.spin_once(node, timeout_sec=0.01)
    flooder = subprocess.Popen([sys.executable, str(FLOODER), RIG, str(args.count)],
                               stdout=subprocess.PIPE, text=True)
    start = time.monotonic()
    while flooder.poll() is None:
        rclpy.spin_once(node, timeout_sec=0.001)
    end = time.monotonic()
    print(flooder.stdout.read().strip())
    after = node.create_publisher(TwistStamped, f"{RIG}/cmd/top_drive", QOS)
    cmd = TwistStamped()
    cmd.header.frame_id, cmd.twist.angular.z = "top_drive", 9.0
    while after.get_subscription_count() == 0:
        rclpy.spin_once(node, timeout_sec=0.01)
    sent = time.monotonic()
    after.publish(cmd)
    while (not speeds or speeds[-1] != 9.0) and time.monotonic() - sent < 30:
        rclpy.spin_once(node, timeout_sec=0.001)
    applied = time.monotonic() - sent if speeds[-1] == 9.0 else None
    end_wait = time.monotonic() + 1.5
    while time.monotonic() < end_wait:
        rclpy.spin_once(node, timeout_sec=0.01)
    node_proc.send_signal(signal.SIGINT)
    node_proc.wait(timeout=20)
    t = np.array(arrivals)
    during = t[(t >= start) & (t <= end)]
    gaps = np.diff(during) * 1e3
    window = [v for w, v in diagnostics if start <= w <= end + 1.0]
    rates = [float(v["tick_rate_hz"]) for v in window]
    longest = max((float(v.get("tick_period_max_ms", "nan")) for v in window), default=math.nan)
    print(f"during the flood ({end - start:.2f} s{', recording' if args.record else ''}): "
          f"{during.size} joint_states ({during.size / (end - start):.0f}/s); gap between "
          f"arrivals p50 {np.percentile(gaps, 50):.2f} ms, p99 {np.percentile(gaps, 99):.2f} "
          f"ms, max {gaps.max():.2f} ms")
    print(f"/diagnostics during the flood: {len(rates)} messages, tick_rate_hz "
          f"{min(rates, default=math.nan):.0f}-{max(rates, default=math.nan):.0f}, longest "
          f"tick period in the node {longest:.2f} ms")
    if diagnostics:
        last = diagnostics[-1][1]
        print("node's command counters: " + ", ".join(
            f"{k} {v}" for k, v in last.items() if k.startswith("commands")))
    print("command after the flood: " + (f"applied {1e3 * applied:.1f} ms after it was sent"
                                         if applied is not None else "NOT applied within 30 s"))
    node.destroy_node()
    rclpy.shutdown()
    tmp.cleanup()


if __name__ == "__main__":
    main()
