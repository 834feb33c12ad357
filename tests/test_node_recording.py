"""Recording inside the node: a session bag read by independent readers, SIGKILL recovery,
and an unwritable path that stops recording but not the simulation."""

from __future__ import annotations

import signal
import time

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import TwistStamped
from mcap_ros2.reader import read_ros2_messages
from rosbags.interfaces import QosReliability
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore
from rosutil import NodeProcess, spin_for, wait_for
from std_msgs.msg import Bool

from drill_sim.bag import reader

OUTPUTS = {"/rec/drill_sim/bit/wrench", "/rec/drill_sim/bit/twist",
           "/rec/drill_sim/bit/stick_slip", "/rec/drill_sim/top_drive/wrench",
           "/rec/drill_sim/bit/depth_of_cut", "/rec/drill_sim/bit/hole_depth",
           "/rec/drill_sim/joint_states"}


def _wait_running(ros, ns: str) -> list[bool]:
    seen: list[bool] = []
    ros.create_subscription(Bool, f"{ns}/drill_sim/bit/stick_slip", seen.append, 100)
    wait_for(lambda: len(seen) > 50, ros, 30.0, f"outputs of the rig in {ns}")
    return seen


def test_recorded_session_is_read_by_rosbags_and_mcap_ros2(ros, tmp_path):
    bag = tmp_path / "session"
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/rec", "-p",
                     f"record:={bag}"):
        _wait_running(ros, "/rec")
        pub = ros.create_publisher(TwistStamped, "/rec/drill_sim/cmd/top_drive", 10)
        wait_for(lambda: pub.get_subscription_count() > 0, ros, 10.0, "command subscription")
        msg = TwistStamped()
        msg.header.frame_id = "top_drive"
        msg.twist.angular.z = 7.0
        for _ in range(5):
            pub.publish(msg)
            spin_for(ros, 0.1)
        spin_for(ros, 0.5)
    store = get_typestore(Stores.ROS2_JAZZY)
    with Reader(bag) as r:
        counts = {c.topic: c.msgcount for c in r.connections}
        assert OUTPUTS <= set(counts)
        assert len({counts[t] for t in OUTPUTS}) == 1 and counts["/rec/drill_sim/bit/wrench"] > 500
        assert counts["/rec/drill_sim/cmd/top_drive"] == 5
        types = {c.topic: c.msgtype for c in r.connections}
        assert types["/rec/drill_sim/joint_states"] == "sensor_msgs/msg/JointState"
        assert all(c.ext.offered_qos_profiles[0].reliability == QosReliability.RELIABLE
                   for c in r.connections if c.topic in OUTPUTS)
        wobs = [store.deserialize_cdr(raw, c.msgtype).wrench.force.z
                for c, _, raw in r.messages() if c.topic == "/rec/drill_sim/bit/wrench"]
        assert wobs[0] == pytest.approx(100e3, rel=1e-6)            # steady start at 100 kN
        cmds = [store.deserialize_cdr(raw, c.msgtype).twist.angular.z
                for c, _, raw in r.messages() if c.topic == "/rec/drill_sim/cmd/top_drive"]
        assert cmds == [7.0] * 5
    decoded = sum(1 for _ in read_ros2_messages(str(bag / "session_0.mcap")))
    assert decoded == sum(counts.values())
    meta = reader.info(bag).metadata
    assert meta["session"]["preset"] == "base" and "command_line" in meta["session"]
    assert float(meta["groups"]["psi"]) == pytest.approx(13.73, rel=0.01)
    assert meta["parameters"]["torsional_stiffness_nm_per_rad"].startswith("938")


def test_sigkill_loses_at_most_the_last_second_and_repair_recovers(ros, tmp_path):
    bag = tmp_path / "killed"
    proc = NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/kill", "-p",
                       f"record:={bag}")
    _wait_running(ros, "/kill")
    spin_for(ros, 3.0)
    killed_ns = time.time_ns()
    proc.proc.send_signal(signal.SIGKILL)
    proc.proc.wait(timeout=10)
    assert not (bag / "metadata.yaml").exists()
    found = reader.info(bag)
    assert found.message_count > 1000
    assert killed_ns - found.end_ns < 1.5e9                 # at most the last second lost
    repaired = reader.repair(bag)
    assert repaired.message_count == found.message_count and not repaired.problems
    with Reader(bag) as r:
        assert r.message_count == found.message_count


def test_unwritable_record_path_keeps_the_simulation_running(ros, tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a directory")
    statuses: list[DiagnosticStatus] = []
    ros.create_subscription(DiagnosticArray, "/diagnostics", lambda m: statuses.extend(
        s for s in m.status if s.name.startswith("unwritable")), 10)
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/nowrite", "-r",
                     "__node:=unwritable", "-p", f"record:={blocker}/bag"):
        seen: list[bool] = []
        ros.create_subscription(Bool, "/nowrite/unwritable/bit/stick_slip", seen.append, 100)
        wait_for(lambda: len(seen) > 50, ros, 30.0, "outputs despite the bad record path")
        wait_for(lambda: any(s.level == DiagnosticStatus.ERROR for s in statuses), ros, 10.0,
                 "an ERROR status about recording")
    error = next(s for s in statuses if s.level == DiagnosticStatus.ERROR)
    assert "not recording" in error.message and "a_file" in error.message


def test_recording_splits_by_duration(ros, tmp_path):
    bag = tmp_path / "split"
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/split", "-p",
                     f"record:={bag}", "-p", "record_split_duration_s:=1.0"):
        _wait_running(ros, "/split")
        spin_for(ros, 2.5)
    assert len(list(bag.glob("split_*.mcap"))) >= 3
    with Reader(bag) as r:
        assert r.message_count == reader.info(bag).message_count > 1000


def test_bag_metrics_export_and_plot_of_a_recorded_stick_slip_session(ros, tmp_path):
    """20 s of the base rig at 60 rpm and 100 kN, recorded at 10x real time: the bag's
    metrics show stick-slip and meet the averaged invariants <WOB> = W0, <Omega> = Omega0."""
    import json
    import subprocess

    from conftest import installed
    bag = tmp_path / "stickslip"
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/ss", "-p",
                     f"record:={bag}", "-p", "real_time_factor:=10.0"):
        _wait_running(ros, "/ss")
        spin_for(ros, 2.5)
    exe = installed("drill_sim")
    proc = subprocess.run([exe, "bag", "metrics", str(bag), "--start", "12", "--json"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    m = json.loads(proc.stdout)
    assert m["stick_fraction"] > 0.2 and m["ssi"] > 1.0
    assert m["mean_wob_n"] == pytest.approx(100e3, rel=0.02)
    assert m["mean_bit_speed_rad_s"] == pytest.approx(2 * 3.141592653589793, rel=0.1)
    csv, png = tmp_path / "s.csv", tmp_path / "s.png"
    for tool, out in (("export", csv), ("plot", png)):
        done = subprocess.run([exe, "bag", tool, str(bag), "--out", str(out)],
                              capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
    header = csv.read_text().splitlines()[0].split(",")
    assert header[0] == "time_s" and "wob_n" in header and "bit_speed_rad_s" in header
    assert png.read_bytes()[:4] == b"\x89PNG"
