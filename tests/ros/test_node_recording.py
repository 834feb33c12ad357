"""Recording inside the node: a session bag read by independent readers, SIGKILL recovery,
and an unwritable path that stops recording but not the simulation."""

from __future__ import annotations

import json
import signal
import subprocess
import time

import pytest
from conftest import installed
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import TwistStamped, WrenchStamped
from mcap_ros2.reader import read_ros2_messages
from rosbags.interfaces import QosReliability
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore
from rosgraph_msgs.msg import Clock
from rosutil import NodeProcess, call_service, set_double, spin_for, wait_for
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool
from std_srvs.srv import Trigger

from drill_sim.bag import reader
from drill_sim.bag.writer import BagWriter
from drill_sim.core import load_preset

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
        msg.header.stamp.sec = -5                  # a stamp before 1970: recorded, no crash
        pub.publish(msg)
        spin_for(ros, 0.5)
    store = get_typestore(Stores.ROS2_JAZZY)
    with Reader(bag) as r:
        counts = {c.topic: c.msgcount for c in r.connections}
        assert OUTPUTS <= set(counts)
        assert len({counts[t] for t in OUTPUTS}) == 1 and counts["/rec/drill_sim/bit/wrench"] > 500
        assert counts["/rec/drill_sim/cmd/top_drive"] == 6
        types = {c.topic: c.msgtype for c in r.connections}
        assert types["/rec/drill_sim/joint_states"] == "sensor_msgs/msg/JointState"
        assert all(c.ext.offered_qos_profiles[0].reliability == QosReliability.RELIABLE
                   for c in r.connections if c.topic in OUTPUTS)
        wobs = [store.deserialize_cdr(raw, c.msgtype).wrench.force.z
                for c, _, raw in r.messages() if c.topic == "/rec/drill_sim/bit/wrench"]
        assert wobs[0] == pytest.approx(100e3, rel=1e-6)            # steady start at 100 kN
        cmds = [store.deserialize_cdr(raw, c.msgtype).twist.angular.z
                for c, _, raw in r.messages() if c.topic == "/rec/drill_sim/cmd/top_drive"]
        assert cmds == [7.0] * 6
        statuses = [store.deserialize_cdr(raw, c.msgtype).status[0]
                    for c, _, raw in r.messages() if c.topic == "/diagnostics"]
        assert statuses and statuses[0].name == "drill_sim: rig"    # /diagnostics recorded
        assert "regime" in {kv.key for kv in statuses[-1].values}
    decoded = sum(1 for _ in read_ros2_messages(str(bag / "session_0.mcap")))
    assert decoded == sum(counts.values())
    meta = reader.info(bag).metadata
    assert meta["session"]["preset"] == "base" and "command_line" in meta["session"]
    assert float(meta["groups"]["psi"]) == pytest.approx(13.73, rel=0.01)
    figures = {k: float(v) for k, v in meta["figures"].items()}    # the rig's key figures
    assert figures["t_star_s"] == pytest.approx(0.210, rel=0.01)
    assert figures["torsional_frequency_hz"] == pytest.approx(0.756, rel=0.01)
    assert figures["axial_frequency_hz"] == pytest.approx(5.61, rel=0.01)
    assert figures["submerged_weight_n"] == pytest.approx(338.4e3, rel=0.001)
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


@pytest.mark.parametrize("where, fragment", [
    ("a_file/bag", "Not a directory; expected a new bag directory in an existing folder"),
    ("taken", "already exists; choose a new directory"),
    ("no/such/bag", "does not exist"),
])
def test_a_record_path_it_cannot_use_stops_the_node_before_it_runs(tmp_path, where, fragment):
    """A session asked to be recorded and not recorded would be lost: the node refuses at
    start, in one line (as drill_sim run --record and drill_sim_record -o do), and writes
    nothing."""
    (tmp_path / "a_file").write_text("not a directory")
    (tmp_path / "taken").mkdir()
    before = sorted(tmp_path.rglob("*"))
    proc = NodeProcess("drill_sim_node", "--ros-args", "-p", f"record:={tmp_path / where}")
    code, out = proc.proc.wait(timeout=60), proc.proc.stdout.read()
    lines = out.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in out, out
    assert f"parameter record = '{tmp_path / where}'" in lines[0] and fragment in lines[0]
    assert "(nothing was run)" in lines[0]
    assert sorted(tmp_path.rglob("*")) == before


def test_a_recording_that_fails_later_stops_and_leaves_the_simulation_running(ros, tmp_path):
    """Writing fails mid-session (the next split file cannot be created: the bag's folder was
    replaced by a file): an ERROR on /diagnostics says so, the outputs go on, the node ends
    normally, and what was written before stays readable."""
    bag, moved = tmp_path / "bag", tmp_path / "moved"
    statuses: list[DiagnosticStatus] = []
    sub = ros.create_subscription(DiagnosticArray, "/diagnostics", lambda m: statuses.extend(
        s for s in m.status if s.name.startswith("failing")), 10)
    seen: list[bool] = []
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/failing", "-r",
                     "__node:=failing", "-p", f"record:={bag}",
                     "-p", "record_split_duration_s:=1.0") as rig:
        flag = ros.create_subscription(Bool, "/failing/failing/bit/stick_slip", seen.append, 100)
        wait_for(lambda: len(seen) > 50, ros, 30.0, "the rig's outputs")
        bag.rename(moved)
        bag.write_text("not a directory any more")
        wait_for(lambda: any(s.level == DiagnosticStatus.ERROR for s in statuses), ros, 15.0,
                 "an ERROR status about recording")
        n = len(seen)
        wait_for(lambda: len(seen) > n + 50, ros, 10.0, "outputs after the failure")
        code, out = rig.stop()
    ros.destroy_subscription(sub)
    ros.destroy_subscription(flag)
    error = next(s for s in statuses if s.level == DiagnosticStatus.ERROR)
    assert code == 0 and "recording stopped" in error.message, (error.message, out)
    found = reader.info(moved)          # the files written before the failure, intact
    assert found.message_count > 1000 and not found.problems, found.problems


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
    done = _resim(bag)                  # real-time mode: ticks from the wall clock
    assert done.returncode == 0, done.stdout + done.stderr
    assert "real-time session" in done.stdout and "reproduced exactly" in done.stdout


def _resim(bag, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([installed("drill_sim"), "bag", "resim", str(bag), *extra],
                          capture_output=True, text=True, timeout=300)


def test_resim_reproduces_a_sim_time_session_with_commands_reset_and_changes(ros, tmp_path):
    """A sim-time session (/clock, back to back) with commands, a refused command, a reset and
    a model-parameter change: the re-run equals the recording bit for bit. The same bag
    without its events is no longer reproduced: the comparison has teeth."""
    bag = tmp_path / "simtime"
    weight = load_preset("base").rig.submerged_weight_n
    clock: list[float] = []
    ros.create_subscription(Clock, "/clock", lambda m: clock.append(
        m.clock.sec + 1e-9 * m.clock.nanosec), 10)
    rig = "/resim/drill_sim"
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/resim", "-p",
                     f"record:={bag}", "-p", "publish_clock:=true", "-p", "max_speed:=true",
                     "-p", "rate_hz:=200.0"):
        speed = ros.create_publisher(TwistStamped, f"{rig}/cmd/top_drive", 10)
        hook = ros.create_publisher(WrenchStamped, f"{rig}/cmd/hook_load", 10)
        wait_for(lambda: speed.get_subscription_count() and hook.get_subscription_count(),
                 ros, 30.0, "the rig's command subscriptions")

        def at(t: float) -> None:
            wait_for(lambda: clock and clock[-1] > t, ros, 60.0, f"simulated time {t} s")

        def command(pub, msg, value) -> None:
            msg.header.frame_id = "top_drive"
            if isinstance(msg, TwistStamped):
                msg.twist.angular.z = value
            else:
                msg.wrench.force.z = value
            pub.publish(msg)

        at(0.5)
        command(speed, TwistStamped(), 12.0)
        at(1.5)
        command(hook, WrenchStamped(), weight - 60e3)
        command(hook, WrenchStamped(), float("nan"))               # refused
        at(2.5)
        assert call_service(ros, Trigger, f"{rig}/reset", Trigger.Request()).success
        at(3.5)
        assert set_double(ros, rig, "friction_coefficient", 0.45).successful
        command(speed, TwistStamped(), 4.0)
        speeds: list[float] = []
        ros.create_subscription(JointState, f"{rig}/joint_states",
                                lambda m: speeds.append(m.velocity[0]), 100)
        wait_for(lambda: speeds and speeds[-1] == 4.0, ros, 30.0, "the last command applied")
        at(max(5.0, clock[-1] + 0.5))
    done = _resim(bag, "--json")
    assert done.returncode == 0, done.stdout + done.stderr
    r = json.loads(done.stdout)
    assert r["exact"] and r["mode"] == "sim-time" and r["samples"] > 900
    assert (r["commands"], r["refused"]) == (3, 1)
    assert r["events"] == ["reset", "parameters"]
    # the same bag with its events left out: the reset and the change are missing
    found = reader.info(bag)
    cut = tmp_path / "no_events"
    with BagWriter(cut, metadata=found.metadata) as w:
        for name, t in found.topics.items():
            w.add_topic(name, t.type_name)
        for m in reader.read_messages(bag):
            if not m.topic.endswith("/events"):
                w.write(m.topic, m.data, m.log_time_ns, m.publish_time_ns)
    done = _resim(cut)
    assert done.returncode == 1, done.stdout + done.stderr
    assert "differs from the recording" in done.stdout
