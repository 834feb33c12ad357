"""The node's ``string_model`` parameter: a session on the distributed string is recorded with
its model and pipe, and ``drill_sim bag resim`` reproduces it bit for bit (and only with them)."""

from __future__ import annotations

import json
import subprocess

from conftest import installed
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rosgraph_msgs.msg import Clock
from rosutil import NodeProcess, call_service, set_double, wait_for
from std_srvs.srv import Trigger

from drill_sim.bag import reader
from drill_sim.bag.writer import BagWriter
from drill_sim.core import load_preset


def _resim(bag) -> dict:
    done = subprocess.run([installed("drill_sim"), "bag", "resim", str(bag), "--json"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode in (0, 1), done.stdout + done.stderr
    return json.loads(done.stdout)


def _with_metadata(src, dst, change) -> None:
    """A copy of bag ``src`` whose metadata ``change`` edited."""
    found = reader.info(src)
    meta = {k: dict(v) for k, v in found.metadata.items()}
    change(meta)
    with BagWriter(dst, metadata=meta) as w:
        for name, t in found.topics.items():
            w.add_topic(name, t.type_name)
        for m in reader.read_messages(src):
            w.write(m.topic, m.data, m.log_time_ns, m.publish_time_ns)


def test_distributed_session_is_recorded_and_resimulated_exactly(ros, tmp_path):
    """Sim-time session, string_model:=distributed, with a command, a reset and a refused
    model-parameter change (the distributed state cannot be carried to new parameters): the
    re-run is exact; the same bag re-run as lumped, or with another pipe, is not."""
    bag = tmp_path / "string"
    rig = "/strm/drill_sim"
    clock: list[float] = []
    ros.create_subscription(Clock, "/clock", lambda m: clock.append(
        m.clock.sec + 1e-9 * m.clock.nanosec), 10)
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/strm", "-p",
                     f"record:={bag}", "-p", "publish_clock:=true", "-p", "max_speed:=true",
                     "-p", "rate_hz:=200.0", "-p", "string_model:=distributed"):
        speed = ros.create_publisher(TwistStamped, f"{rig}/cmd/top_drive", 10)
        wait_for(lambda: speed.get_subscription_count() > 0, ros, 30.0, "command subscription")

        def at(t: float) -> None:
            wait_for(lambda: clock and clock[-1] > t, ros, 60.0, f"simulated time {t} s")

        at(0.5)
        msg = TwistStamped()
        msg.header.frame_id = "top_drive"
        msg.twist.angular.z = 9.0
        speed.publish(msg)
        at(1.5)
        assert call_service(ros, Trigger, f"{rig}/reset", Trigger.Request()).success
        refused = set_double(ros, rig, "friction_coefficient", 0.45)
        assert not refused.successful and "distributed" in refused.reason
        at(3.0)
    meta = reader.info(bag).metadata
    assert meta["parameters"]["string_model"] == "distributed"
    assert float(meta["string"]["pipe_length_m"]) == load_preset("base").string.pipe_length_m
    r = _resim(bag)
    assert r["exact"] and r["samples"] > 500 and r["events"] == ["reset"], r
    assert r["commands"] == 1
    lumped = tmp_path / "as_lumped"
    _with_metadata(bag, lumped, lambda m: m["parameters"].update(string_model="lumped"))
    assert not _resim(lumped)["exact"]
    longer = tmp_path / "longer_pipe"
    _with_metadata(bag, longer, lambda m: m["string"].update(pipe_length_m="1001.0"))
    assert not _resim(longer)["exact"]


def test_distributed_string_under_the_torque_mode_drive_resimulates_exactly(ros, tmp_path):
    """string_model:=distributed with top_drive_mode:=torque: a motor torque command well above
    the steady torque speeds the drive up (its inertia is the pipe's top), and the session's
    re-run is exact."""
    bag = tmp_path / "string_torque"
    rig = "/strq/drill_sim"
    clock: list[float] = []
    speeds: list[float] = []
    ros.create_subscription(Clock, "/clock", lambda m: clock.append(
        m.clock.sec + 1e-9 * m.clock.nanosec), 10)
    ros.create_subscription(TwistStamped, f"{rig}/top_drive/twist",
                            lambda m: speeds.append(m.twist.angular.z), 1000)
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/strq", "-p",
                     f"record:={bag}", "-p", "publish_clock:=true", "-p", "max_speed:=true",
                     "-p", "rate_hz:=200.0", "-p", "string_model:=distributed", "-p",
                     "top_drive_mode:=torque"):
        torque = ros.create_publisher(WrenchStamped, f"{rig}/cmd/top_drive_torque", 10)
        wait_for(lambda: torque.get_subscription_count() > 0 and speeds, ros, 30.0,
                 "the rig running and subscribed")
        speed0 = speeds[-1]
        msg = WrenchStamped()
        msg.header.frame_id = "top_drive"
        msg.wrench.torque.z = 30e3
        torque.publish(msg)
        wait_for(lambda: speeds[-1] > speed0 + 0.5, ros, 60.0, "the drive to speed up")
        t = clock[-1]
        wait_for(lambda: clock[-1] > t + 0.5, ros, 60.0, "half a simulated second more")
    meta = reader.info(bag).metadata
    assert meta["parameters"]["string_model"] == "distributed"
    assert meta["parameters"]["top_drive_mode"] == "torque"
    r = _resim(bag)
    assert r["exact"] and r["commands"] == 1, r


def test_string_model_is_checked_at_start(ros):
    proc = NodeProcess("drill_sim_node", "--ros-args", "-p", "string_model:=rope")
    code = proc.proc.wait(timeout=30)
    out = proc.proc.stdout.read()
    assert code == 2 and "string_model" in out and "distributed" in out
    assert "Traceback" not in out
