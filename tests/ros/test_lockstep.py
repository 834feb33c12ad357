"""Lockstep, with the installed node and a plain-rclpy controller in other processes: two runs of
the same closed loop give the same recorded session byte for byte; a command answering sample k
acts from tick k exactly (the top drive turns at the new speed over the next tick, as the
kinematic law says); /clock advances exactly 1/rate_hz a tick in lockstep and in real time; a
controller that is not there is waited for (warned on /diagnostics, the tick published again)
and picked up when it comes."""

from __future__ import annotations

import itertools
import statistics
import subprocess
import sys
import time
from pathlib import Path

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import TwistStamped
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore
from rosgraph_msgs.msg import Clock
from rosutil import NodeProcess, wait_for

from drill_sim.session.resim import resimulate

CONTROLLER = Path(__file__).with_name("lockstep_controller.py")
TICK_NS = 1_000_000                     # rate_hz 1000
STORE = get_typestore(Stores.ROS2_JAZZY)
LOCKSTEP = ("-p", "publish_clock:=true", "-p", "lockstep:=true")


def _controller(rig: str, *args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, str(CONTROLLER), "--rig", rig, *args],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def _closed_loop(bag: Path, ticks: int) -> None:
    """A rig started paused in lockstep, recording; the PI resumes it and answers ``ticks``
    samples, then stops answering (the rig waits at tick ``ticks``)."""
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/lsk", *LOCKSTEP,
                     "-p", "start_paused:=true", "-p", f"record:={bag}") as node:
        ctl = _controller("/lsk/drill_sim", "--ticks", str(ticks), "--resume")
        out, _ = ctl.communicate(timeout=120)
        assert ctl.returncode == 0 and f"answered {ticks}" in out, out
        code, log = node.stop()
        assert code == 0, log


def _messages(bag: Path) -> list[tuple[str, bytes]]:
    """Every recorded message but /diagnostics and events (wall-clock figures), in order."""
    with Reader(bag) as r:
        return [(c.topic, bytes(raw)) for c, _, raw in r.messages()
                if c.topic != "/diagnostics" and not c.topic.endswith("/events")]


def _stamp_ns(topic: str, raw: bytes) -> int:
    kind = "rosgraph_msgs/msg/Clock" if topic == "/clock" else "sensor_msgs/msg/JointState"
    msg = STORE.deserialize_cdr(raw, kind)
    stamp = msg.clock if topic == "/clock" else msg.header.stamp
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def test_two_runs_of_a_closed_loop_record_the_same_session(tmp_path):
    runs = [tmp_path / "run1", tmp_path / "run2"]
    for bag in runs:
        _closed_loop(bag, 1500)
    first, second = (_messages(b) for b in runs)
    assert first == second                            # byte for byte, in the same order
    commands = [STORE.deserialize_cdr(raw, "geometry_msgs/msg/TwistStamped")
                for t, raw in first if t.endswith("/cmd/top_drive")]
    speeds = [c.twist.angular.z for c in commands]
    assert len(commands) == 1500 and max(speeds) - min(speeds) > 1.0   # the loop did act
    # each command answers the sample before it: stamped k ticks, recorded after sample k
    answered = [c.header.stamp.sec * 1_000_000_000 + c.header.stamp.nanosec for c in commands]
    assert answered == [k * TICK_NS for k in range(1500)]
    clock = [_stamp_ns(t, raw) for t, raw in first if t == "/clock"]
    assert clock == [k * TICK_NS for k in range(1501)]  # exactly 1 ms of simulated time a tick
    joints = [_stamp_ns(t, raw) for t, raw in first if t.endswith("/joint_states")]
    assert joints == clock
    rerun = resimulate(runs[0])
    assert rerun.exact, rerun.explanation()


def test_a_late_controller_is_waited_for_and_its_command_lands_at_the_next_tick(ros, tmp_path):
    """No controller: tick 0 waits, /diagnostics warns, tick 0 is published again every
    lockstep_timeout_s (here 10 ms), and the node's log says so at most once a second (it said
    it every timeout). Then a controller answers sample k with hold speed for k < K and X from
    K on: the top drive turns through hold x tick over tick K-1 and X x tick over K."""
    bag, hold, x, k_step = tmp_path / "late", 2 * 3.141592653589793, 10.0, 40
    samples: list[int] = []
    statuses: list[DiagnosticStatus] = []
    ros.create_subscription(TwistStamped, "/lsl/drill_sim/bit/twist", lambda m: samples.append(
        m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec), 100)
    ros.create_subscription(DiagnosticArray, "/diagnostics",
                            lambda m: statuses.extend(m.status), 100)
    started = time.monotonic()
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/lsl", *LOCKSTEP,
                     "-p", "lockstep_timeout_s:=0.01", "-p", "diagnostics_period_s:=0.1",
                     "-p", f"record:={bag}") as node:
        wait_for(lambda: len(samples) >= 30, ros, 30.0, "tick 0 published again")
        assert set(samples) == {0}                        # waiting at tick 0, not advancing
        wait_for(lambda: any("lockstep: waiting" in s.message for s in statuses), ros, 30.0,
                 "the lockstep warning on /diagnostics")
        warn = next(s for s in statuses if "lockstep: waiting" in s.message)
        assert warn.level == DiagnosticStatus.WARN and "cmd/top_drive" in warn.message
        ctl = _controller("/lsl/drill_sim", "--ticks", "100", "--step-at-s", str(k_step / 1e3),
                          "--step-to", str(x), "--hold-speed", repr(hold))
        out, _ = ctl.communicate(timeout=120)
        assert ctl.returncode == 0 and "answered 100" in out, out
        wait_for(lambda: max(samples) == 100 * TICK_NS, ros, 30.0, "tick 100")
        waited_s = time.monotonic() - started              # at most this long at tick 0
        code, log = node.stop()
        assert code == 0, log
    said = log.count("lockstep: waiting")
    assert 1 <= said <= waited_s + 2, (said, waited_s)
    joints = [STORE.deserialize_cdr(raw, "sensor_msgs/msg/JointState")
              for t, raw in _messages(bag) if t.endswith("/joint_states")]
    stamps = [j.header.stamp.sec * 1_000_000_000 + j.header.stamp.nanosec for j in joints]
    assert stamps == [k * TICK_NS for k in range(101)]      # re-publications not recorded
    angle = [j.position[0] for j in joints]                          # top-drive angle [rad]
    tick_s = TICK_NS * 1e-9
    assert angle[k_step] - angle[k_step - 1] == pytest.approx(hold * tick_s, rel=1e-9)
    assert angle[k_step + 1] - angle[k_step] == pytest.approx(x * tick_s, rel=1e-9)
    assert joints[k_step].velocity[0] == hold and joints[k_step + 1].velocity[0] == x


def test_clock_advances_whole_ticks_in_real_time(ros):
    """Real time at 1000 Hz: every /clock step is a whole number of 1 ms ticks, almost all
    exactly one (a stall, which a loaded machine may cause, advances the ticks it missed)."""
    clocks: list[int] = []
    ros.create_subscription(Clock, "/clock", lambda m: clocks.append(
        m.clock.sec * 1_000_000_000 + m.clock.nanosec), 1000)
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/lsr",
                     "-p", "publish_clock:=true"):
        wait_for(lambda: len(clocks) > 1500, ros, 60.0, "1.5 s of /clock")
    steps = [b - a for a, b in itertools.pairwise(clocks)]
    assert all(s > 0 and s % TICK_NS == 0 for s in steps), sorted(set(steps))[:10]
    assert statistics.median(steps) == TICK_NS
