"""Throughput of ``drill_sim_record`` [issue target: >= 20 000 messages/s without loss].

This process publishes std_msgs/Float64 messages numbered 0..N-1 at --rate messages per second
(bursts every millisecond, reliable, depth 1000) to a recorder in another process; then the bag
is read back and every number must be there exactly once. Prints the achieved publishing rate,
messages lost and the recorder's CPU.

Run: .venv/bin/python benchmarks/bench_record.py [--rate 20000] [--seconds 10]
"""

from __future__ import annotations

import argparse
import itertools
import os
import re
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import Float64

from drill_sim.bag.reader import read_messages

BIN = Path(sys.executable).parent


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--rate", type=float, default=20000.0, help="messages per second")
    parser.add_argument("--seconds", type=float, default=10.0)
    args = parser.parse_args()
    os.environ.setdefault("ROS_DOMAIN_ID", str(100 + os.getpid() % 100))
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    tmp = Path(tempfile.mkdtemp())
    bag = tmp / "bench"
    rec = subprocess.Popen([str(BIN / "drill_sim_record"), "/bench/stream", "-o", str(bag)],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    rclpy.init()
    node = rclpy.create_node("bench_publisher")
    pub = node.create_publisher(Float64, "/bench/stream",
                                QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    end = time.monotonic() + 30
    while pub.get_subscription_count() == 0 and time.monotonic() < end:
        time.sleep(0.01)
    if pub.get_subscription_count() == 0:
        raise SystemExit("the recorder never subscribed")
    n = int(args.rate * args.seconds)
    burst = max(1, int(args.rate / 1000))
    pack = struct.Struct("<4sd").pack
    cpu0 = cpu_seconds(rec.pid)
    t0 = time.perf_counter()
    for i in range(0, n, burst):
        due = t0 + i / args.rate
        while time.perf_counter() < due:
            pass
        for k in range(i, min(i + burst, n)):
            pub.publish(pack(b"\x00\x01\x00\x00", float(k)))
    elapsed = time.perf_counter() - t0
    time.sleep(1.0)                      # let the last messages arrive, then stop the recorder
    cpu = cpu_seconds(rec.pid) - cpu0
    rec.send_signal(signal.SIGINT)
    _, err = rec.communicate(timeout=60)
    reported = re.search(r"LOST (\d+) messages", err)
    node.destroy_node()
    rclpy.shutdown()
    values = [struct.unpack_from("<d", m.data, 4)[0] for m in read_messages(bag)]
    missing = n - len(set(values))
    in_order = all(b > a for a, b in itertools.pairwise(values))
    print(f"published {n} messages in {elapsed:.2f} s ({n / elapsed:.0f} msg/s); recorded "
          f"{len(values)}, lost {missing}, {'in order' if in_order else 'OUT OF ORDER'}; "
          f"recorder CPU {100 * cpu / (elapsed + 1.0):.0f} % of one core; the recorder "
          f"reported {reported.group(1) if reported else 0} lost")
    shutil.rmtree(tmp)


if __name__ == "__main__":
    main()
