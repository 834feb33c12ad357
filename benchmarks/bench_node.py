"""Speed of the rig node (issue targets in brackets), each from a second process:

  - at 1000 Hz with every output published and one external subscriber, over --seconds:
    achieved rate [>= 99.5 % of nominal], p99 period between received samples [<= 1.2 ms],
    CPU of the node process [<= 40 % of one core];
  - the same with the node recording everything (record:=...) [CPU added <= 10 % of one core];
  - command-to-response latency: a top-drive command published -> the first joint_states
    sample carrying it received back [p50 <= 1.5 ms, p99 <= 3 ms], without and with recording;
  - max_speed with publish_clock: simulated seconds per wall second [>= 20].

With --top-drive-mode torque: only the 1000 Hz figures (without and with recording), the node
in torque mode and the benchmark closing the loop like a controller: for every
~/top_drive/twist it receives it publishes a motor torque on ~/cmd/top_drive_torque (a PI on
the top-drive speed, 60 rpm), so the node takes a command every tick.

With --sensor-profile NAME every node runs that sensor profile (msg_docs/sensors.md);
--string-model lumped|distributed sets every node's string_model, --preset NAME its preset;
--rate-only prints only the 1000 Hz rate and CPU.

Beside each 1000 Hz run, a do-nothing 1 kHz sleeper in a third process (bench_wakeups.py)
measures this machine's own wake-up floor over the same seconds, under the same load: a node
cannot be more on time than that, so its figures are to be read against it.

--thread-priority N runs the nodes with thread_priority:=N (their loop under SCHED_FIFO) and
the benchmark's own thread at N too, as a controller under test on a real-time machine would.
--cpu-wakeup-latency-us N runs the nodes with cpu_wakeup_latency_us:=N (no idle core of the
machine sleeps deeper than N us while a node runs; 0: they poll), which the benchmark, its
controller and the floor sleeper beside then share, as on a machine set up for real time.

Run: .venv/bin/python benchmarks/bench_node.py [--seconds 30] [--top-drive-mode torque]
         [--sensor-profile NAME] [--string-model distributed] [--rate-only]
         [--thread-priority 50] [--cpu-wakeup-latency-us 0]
"""

from __future__ import annotations

import argparse
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
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rclpy.experimental import EventsExecutor
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState

from drill_sim.ros.wakeups import run_at_priority

BIN = Path(sys.executable).parent
NODE_ARGS: list[str] = []       # parameters every node started here gets (sensors, string)
EXECUTOR: list = []             # the benchmark's one executor, made at the first spin


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def start(*args: str) -> subprocess.Popen:
    return subprocess.Popen([str(BIN / "drill_sim_node"), "--ros-args", *NODE_ARGS, *args],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def spin(node, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        spin_once(node, 0.001)


def spin_once(node, timeout_s: float) -> None:
    """The benchmark's own callbacks, under rclpy's EventsExecutor: the SingleThreadedExecutor
    took ~0.6 of a core at 1 kHz, beside the node on a 2-core machine (its received periods
    measured the benchmark's own delays as much as the node's)."""
    if not EXECUTOR:
        EXECUTOR.append(EventsExecutor())
        EXECUTOR[0].add_node(node)
    EXECUTOR[0].spin_once(timeout_sec=timeout_s)


class TorqueController:
    """A PI on the top-drive speed [rad/s] -> motor torque [N m], one command per sample
    received: the load of a stick-slip controller closing the loop at the node's rate. It
    reads what a controller under test reads: ~/measured/ (the sensor profile's)."""

    KP_NM_S_RAD, KI_NM_RAD, SET_RAD_S, DT_S = 15e3, 14.5e3, 2 * np.pi, 1e-3

    def __init__(self, node, ns: str) -> None:
        self.pub = node.create_publisher(WrenchStamped, f"{ns}/drill_sim/cmd/top_drive_torque",
                                         10)
        self.integral_nm: float | None = None
        self.msg = WrenchStamped()
        self.msg.header.frame_id = "top_drive"
        self.sent = 0
        node.create_subscription(WrenchStamped, f"{ns}/drill_sim/measured/top_drive/motor_wrench",
                                 self._start, 10)
        node.create_subscription(TwistStamped, f"{ns}/drill_sim/measured/top_drive/twist",
                                 self._on_speed, 1000)

    def _start(self, m: WrenchStamped) -> None:
        if self.integral_nm is None:                 # bumpless: from the torque applied
            self.integral_nm = m.wrench.torque.z

    def _on_speed(self, m: TwistStamped) -> None:
        if self.integral_nm is None:
            return
        error = self.SET_RAD_S - m.twist.angular.z
        self.integral_nm += self.KI_NM_RAD * error * self.DT_S
        self.msg.header.stamp = m.header.stamp
        self.msg.wrench.torque.z = float(np.clip(self.integral_nm + self.KP_NM_S_RAD * error,
                                                 -6e4, 6e4))
        self.pub.publish(self.msg)
        self.sent += 1


def rate_and_cpu(node, seconds: float, record: str = "", mode: str = "kinematic") -> float:
    ns = ("/bench_rec" if record else "/bench") + ("_torque" if mode == "torque" else "")
    proc = start("-r", f"__ns:={ns}", "-p", f"top_drive_mode:={mode}",
                 *(("-p", f"record:={record}") if record else ()))
    controller = TorqueController(node, ns) if mode == "torque" else None
    arrivals: list[float] = []
    p99s: list[float] = []
    node.create_subscription(JointState, f"{ns}/drill_sim/joint_states",
                             lambda m: arrivals.append(time.perf_counter()), 1000)
    node.create_subscription(DiagnosticArray, "/diagnostics", lambda m: p99s.extend(
        float(kv.value) for kv in m.status[0].values if kv.key == "tick_period_p99_ms"), 10)
    end = time.monotonic() + 60
    while len(arrivals) < 2000 and time.monotonic() < end:
        spin_once(node, 0.01)
    arrivals.clear()
    p99s.clear()
    cpu0, wall0 = cpu_seconds(proc.pid), time.monotonic()
    floor = subprocess.Popen([sys.executable, str(Path(__file__).parent / "bench_wakeups.py"),
                              "--seconds", f"{seconds:g}"], stdout=subprocess.PIPE, text=True)
    spin(node, seconds)
    cpu = (cpu_seconds(proc.pid) - cpu0) / (time.monotonic() - wall0)
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=20)
    beside = floor.communicate(timeout=60)[0].strip()
    t = np.array(arrivals)
    periods = np.diff(t) * 1e3
    rate = (len(t) - 1) / (t[-1] - t[0])
    loop = (f", top drive in torque mode, {controller.sent / seconds:.0f} torque commands/s "
            "back" if controller is not None else "")
    print(f"1000 Hz, all outputs{', recording' if record else ''}, one external subscriber"
          f"{loop}, {' '.join(NODE_ARGS[1::2])}, {seconds:g} s: achieved "
          f"{rate:.1f} Hz ({100 * rate / 1000:.2f} %), received period p50 "
          f"{np.percentile(periods, 50):.3f} ms, p99 {np.percentile(periods, 99):.3f} ms; "
          f"tick period p99 in the node per 1 s window: median {np.median(p99s):.3f} ms, "
          f"worst {max(p99s):.3f} ms; "
          f"node CPU {100 * cpu:.1f} % of one core")
    print(f"  beside it, {beside}")
    return cpu


def latency(node, samples: int = 2000, record: str = "") -> None:
    ns = "/lat_rec" if record else "/lat"
    proc = start("-r", f"__ns:={ns}", *(("-p", f"record:={record}") if record else ()))
    pub = node.create_publisher(TwistStamped, f"{ns}/drill_sim/cmd/top_drive", 10)
    state = {"value": None, "sent": 0.0}
    lat: list[float] = []

    def on_joints(m: JointState) -> None:
        if state["value"] is not None and m.velocity[0] == state["value"]:
            lat.append(time.perf_counter() - state["sent"])
            state["value"] = None

    node.create_subscription(JointState, f"{ns}/drill_sim/joint_states", on_joints, 1000)
    while pub.get_subscription_count() == 0:
        spin_once(node, 0.01)
    spin(node, 1.0)
    msg = TwistStamped()
    msg.header.frame_id = "top_drive"
    for i in range(samples):
        value = 6.0 + 0.001 * (i % 100)
        msg.twist.angular.z = value
        state["value"], state["sent"] = value, time.perf_counter()
        pub.publish(msg)
        end = time.monotonic() + 0.5
        while state["value"] is not None and time.monotonic() < end:
            spin_once(node, 0.0005)
        spin(node, 0.002 + 0.0007 * (i % 3))            # vary the phase against the tick
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=20)
    ms = np.array(lat) * 1e3
    print(f"command-to-response latency{' while recording' if record else ''} over {len(ms)} "
          f"commands: p50 {np.percentile(ms, 50):.3f} ms, p99 {np.percentile(ms, 99):.3f} ms")


def max_speed(node, rate_hz: float, seconds: float = 10.0) -> None:
    proc = start("-r", "__ns:=/max", "-p", "publish_clock:=true", "-p", "max_speed:=true",
                 "-p", f"rate_hz:={rate_hz}")
    clocks: list[tuple[float, float]] = []
    node.create_subscription(Clock, "/clock", lambda m: clocks.append(
        (time.monotonic(), m.clock.sec + 1e-9 * m.clock.nanosec)), 1000)
    while len(clocks) < 100:
        spin_once(node, 0.01)
    clocks.clear()
    spin(node, seconds)
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=20)
    c = np.array(clocks)
    speedup = (c[-1, 1] - c[0, 1]) / (c[-1, 0] - c[0, 0])
    print(f"max_speed with /clock, all topics every tick of {1e3 / rate_hz:g} ms simulated "
          f"(rate_hz {rate_hz:g}): {speedup:.1f} x real time")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--top-drive-mode", choices=("kinematic", "torque"),
                        default="kinematic")
    parser.add_argument("--sensor-profile", default="ideal")
    parser.add_argument("--string-model", choices=("lumped", "distributed"), default=None)
    parser.add_argument("--preset", default=None, help="every node's preset (default: base)")
    parser.add_argument("--rate-only", action="store_true")
    parser.add_argument("--thread-priority", type=int, default=0, metavar="PRIORITY",
                        help="the nodes' thread_priority (SCHED_FIFO), and the benchmark's "
                        "own thread (subscriber, controller) at the same priority")
    parser.add_argument("--cpu-wakeup-latency-us", type=int, default=-1, metavar="US",
                        help="the nodes' cpu_wakeup_latency_us (0: idle cores poll while a "
                        "node runs; needs root)")
    args = parser.parse_args()
    NODE_ARGS.extend(["-p", f"sensor_profile:={args.sensor_profile}"])
    if args.cpu_wakeup_latency_us >= 0:
        NODE_ARGS.extend(["-p", f"cpu_wakeup_latency_us:={args.cpu_wakeup_latency_us}"])
    if args.thread_priority:
        NODE_ARGS.extend(["-p", f"thread_priority:={args.thread_priority}"])
    if args.string_model:
        NODE_ARGS.extend(["-p", f"string_model:={args.string_model}"])
    if args.preset:
        NODE_ARGS.extend(["-p", f"preset:={args.preset}"])
    os.environ.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    rclpy.init()
    node = rclpy.create_node("drill_sim_bench")
    if args.thread_priority and (why := run_at_priority(args.thread_priority)):
        raise SystemExit(f"--thread-priority: {why}")
    if args.top_drive_mode == "torque":
        plain = rate_and_cpu(node, args.seconds, mode="torque")
        with tempfile.TemporaryDirectory() as tmp:
            recording = rate_and_cpu(node, args.seconds, record=f"{tmp}/bag", mode="torque")
        print(f"CPU added by in-node recording: {100 * (recording - plain):.1f} % of one core")
        node.destroy_node()
        rclpy.shutdown()
        return
    plain = rate_and_cpu(node, args.seconds)
    if args.rate_only:
        node.destroy_node()
        rclpy.shutdown()
        return
    with tempfile.TemporaryDirectory() as tmp:
        recording = rate_and_cpu(node, args.seconds, record=f"{tmp}/bag")
    print(f"CPU added by in-node recording: {100 * (recording - plain):.1f} % of one core")
    if args.rate_only:
        node.destroy_node()
        rclpy.shutdown()
        return
    latency(node)
    with tempfile.TemporaryDirectory() as tmp:
        latency(node, record=f"{tmp}/bag")
    max_speed(node, 1000.0)
    max_speed(node, 100.0)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
