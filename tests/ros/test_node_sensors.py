"""The installed node's ~/measured/ topics under a noisy user profile: published every tick
beside the exact state, sampled, quantised and noisy as the profile says, recorded, and
reproduced bit for bit by ``bag resim`` from the recorded profile and seed."""

from __future__ import annotations

import csv
import json
import subprocess

import numpy as np
from conftest import installed
from geometry_msgs.msg import WrenchStamped
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore
from rosgraph_msgs.msg import Clock
from rosutil import NodeProcess, call_service, set_string, wait_for
from std_srvs.srv import Trigger

from drill_sim.bag import reader
from drill_sim.bag.writer import BagWriter

PROFILE = """\
description: "noisy test sensors: every effect on every channel, downhole at 20 Hz"
channels:
  surface_torque_nm: {rate_hz: 100.0, delay_s: 0.02, noise_std: 100.0, quantum: 10.0,
                      filter_tau_s: 0.01}
  top_drive_speed_rad_s: {noise_std: 0.01, quantum: 0.001}
  motor_torque_nm: {rate_hz: 50.0, noise_std: 50.0}
  hook_load_n: {rate_hz: 10.0, delay_s: 0.1, noise_std: 1000.0, quantum: 100.0,
                filter_tau_s: 0.2, bias: -500.0}
  wob_n: {rate_hz: 20.0, delay_s: 0.1, noise_std: 2000.0, quantum: 500.0}
  tob_nm: {rate_hz: 20.0, delay_s: 0.1, noise_std: 100.0, quantum: 50.0}
  bit_speed_rad_s: {rate_hz: 20.0, delay_s: 0.1, noise_std: 0.1}
  stick_slip_severity: {rate_hz: 1.0, delay_s: 0.5, window_s: 1.0, quantum: 0.01}
"""
RIG = "/sens/drill_sim"


def _resim(bag) -> dict:
    done = subprocess.run([installed("drill_sim"), "bag", "resim", str(bag), "--json"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode in (0, 1), done.stdout + done.stderr
    return json.loads(done.stdout)


def test_measured_topics_follow_the_profile_and_resim_reproduces_them(ros, tmp_path):
    profile = tmp_path / "noisy.yaml"
    profile.write_text(PROFILE)
    bag = tmp_path / "sensed"
    clock: list[float] = []
    measured: list[float] = []
    ros.create_subscription(Clock, "/clock", lambda m: clock.append(
        m.clock.sec + 1e-9 * m.clock.nanosec), 10)
    ros.create_subscription(WrenchStamped, f"{RIG}/measured/bit/wrench",
                            lambda m: measured.append(m.wrench.force.z), 100)
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/sens", "-p",
                     f"record:={bag}", "-p", "publish_clock:=true", "-p", "max_speed:=true",
                     "-p", "rate_hz:=200.0", "-p", f"sensor_profile:={profile}",
                     "-p", "sensor_seed:=42", "-p", "initial_perturbation:=0.5"):
        # (the bit starts 50 % fast, so its speed swings and the severity is not 0: a steady
        # start showed 0 on both sides of the comparison)
        wait_for(lambda: clock and clock[-1] > 2.0, ros, 60.0, "2 s of simulated time")
        # a reset restarts the sensors too (resim below redoes it)
        assert call_service(ros, Trigger, f"{RIG}/reset", Trigger.Request()).success
        wait_for(lambda: clock and clock[-1] > 4.0 and len(measured) > 800, ros, 60.0,
                 "4 s of simulated time and the measured WOB")
    store = get_typestore(Stores.ROS2_JAZZY)
    series: dict[str, list] = {}
    with Reader(bag) as r:
        for c, _, raw in r.messages():
            if c.topic in (f"{RIG}/bit/wrench", f"{RIG}/measured/bit/wrench",
                           f"{RIG}/measured/top_drive/wrench",
                           f"{RIG}/measured/bit/stick_slip_severity"):
                series.setdefault(c.topic, []).append(store.deserialize_cdr(raw, c.msgtype))
    exact = np.array([m.wrench.force.z for m in series[f"{RIG}/bit/wrench"]])
    wob = np.array([m.wrench.force.z for m in series[f"{RIG}/measured/bit/wrench"]])
    hook = np.array([m.wrench.force.z for m in series[f"{RIG}/measured/top_drive/wrench"]])
    severity = np.array([m.data for m in series[f"{RIG}/measured/bit/stick_slip_severity"]])
    assert severity.max() > 0.1                                  # something to compare below
    assert len(wob) == len(exact) > 800                          # every tick, beside the exact
    assert np.array_equal(wob / 500.0, np.round(wob / 500.0))    # quantised to 500 N
    assert np.array_equal(hook / 100.0, np.round(hook / 100.0))
    changes = np.count_nonzero(np.diff(wob))
    assert changes <= len(wob) // 10 + 1                         # 20 Hz held at 200 Hz ticks
    assert changes > len(wob) // 20                              # noise: nearly every sample new
    assert np.abs(wob - exact).max() > 0                         # not the exact state
    span = 5 * 2000.0 + 250.0                                    # 5 sigma of noise, half a step
    assert exact.min() - span <= wob.min() and wob.max() <= exact.max() + span
    # bag export carries what the sensors showed beside the exact state, matched by stamp
    out = tmp_path / "session.csv"
    done = subprocess.run([installed("drill_sim"), "bag", "export", str(bag), "--out", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    assert {f"measured_{c}" for c in ("surface_torque_nm", "hook_load_n",
                                      "top_drive_speed_rad_s", "motor_torque_nm", "wob_n",
                                      "tob_nm", "bit_speed_rad_s")} <= set(rows[0])
    sent = {m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec: m.wrench.force.z
            for m in series[f"{RIG}/measured/bit/wrench"]}
    exported = {int(r["stamp_ns"]): float(r["measured_wob_n"]) for r in rows}
    # (the reset published its new start at the last tick's stamp: matched in order)
    assert len(exported) == len(sent) and all(exported[ns] == v for ns, v in sent.items())
    meta = reader.info(bag).metadata
    assert meta["parameters"]["sensor_seed"] == "42"
    assert json.loads(meta["sensors"]["profile"])["channels"]["wob_n"]["noise_std"] == 2000.0

    r = _resim(bag)
    assert r["exact"] and r["events"] == ["reset"], r
    assert r["max_difference"]["measured wob_n"] == 0.0
    assert r["max_difference"]["measured stick_slip_severity"] == 0.0
    # the comparison has teeth: another seed in the same bag is no longer reproduced
    found = reader.info(bag)
    other = tmp_path / "other_seed"
    meta = {k: dict(v) for k, v in found.metadata.items()}
    meta["parameters"]["sensor_seed"] = "43"
    with BagWriter(other, metadata=meta) as w:
        for name, t in found.topics.items():
            w.add_topic(name, t.type_name)
        for m in reader.read_messages(bag):
            w.write(m.topic, m.data, m.log_time_ns, m.publish_time_ns)
    r = _resim(other)
    assert not r["exact"] and r["worst"]["quantity"].startswith("measured ")
    assert all(r["max_difference"][k] == 0.0 for k in r["max_difference"]
               if not k.startswith("measured "))


def test_on_sample_publishes_each_measured_topic_at_its_sensors_rate(ros, tmp_path):
    """measured_publish switched from every_tick to on_sample while running: from then on
    each ~/measured/ topic comes (and is recorded) only in the ticks one of its channels is
    fresh, at the rate the profile gives it (200 Hz ticks: WOB/TOB at 20 Hz every 10th tick,
    the motor torque at 50 Hz every 4th, the surface torque at 100 Hz every 2nd, the top-drive
    speed, unsampled, every tick); values the same as before (resim exact)."""
    profile = tmp_path / "noisy.yaml"
    profile.write_text(PROFILE)
    bag = tmp_path / "on_sample"
    clock: list[float] = []
    ros.create_subscription(Clock, "/clock", lambda m: clock.append(
        m.clock.sec + 1e-9 * m.clock.nanosec), 10)
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/sens", "-p",
                     f"record:={bag}", "-p", "publish_clock:=true", "-p", "max_speed:=true",
                     "-p", "rate_hz:=200.0", "-p", f"sensor_profile:={profile}"):
        wait_for(lambda: clock and clock[-1] > 1.0, ros, 60.0, "1 s of simulated time")
        assert set_string(ros, RIG, "measured_publish", "on_sample").successful
        switched = clock[-1]
        wait_for(lambda: clock[-1] > switched + 2.0, ros, 60.0, "2 s more")
    stamps: dict[str, list[int]] = {}
    with Reader(bag) as r:
        for c, _, raw in r.messages():
            if c.msgtype.endswith(("Stamped", "JointState")) and c.topic.startswith(RIG):
                sec, nsec = np.frombuffer(raw[4:12], "<i4")
                stamps.setdefault(c.topic, []).append(int(sec) * 10**9 + int(nsec) % 2**32)
    joints = np.array(stamps[f"{RIG}/joint_states"])
    assert np.all(np.diff(joints) == 5_000_000)                   # every 5 ms tick recorded
    for topic, every in (("bit/wrench", 10), ("top_drive/motor_wrench", 4),
                         ("top_drive/wrench", 2), ("top_drive/twist", 1)):
        ticks = np.diff(np.array(stamps[f"{RIG}/measured/{topic}"])) // 5_000_000
        if every == 1:
            assert len(ticks) > 550 and np.all(ticks == 1), topic
            continue
        before = np.argmax(ticks != 1)
        after = ticks[before + 1:]                   # past the tick the switch came in
        assert before > 150 and np.all(ticks[:before] == 1), topic    # every tick, 1 s
        assert len(after) > 350 // every and np.all(after == every), (topic, set(after))
    r = _resim(bag)
    assert r["exact"], r
    assert r["max_difference"]["measured wob_n"] == 0.0


def test_a_bad_sensor_profile_stops_the_node_with_one_clear_line(ros, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("channels:\n  wob_n: {delay_s: -1.0}\n")
    for value, words in (("no_such_profile", "neither a shipped sensor profile"),
                         (str(bad), "delay_s = -1.0: expected a non-negative number")):
        node = NodeProcess("drill_sim_node", "--ros-args", "-p", f"sensor_profile:={value}")
        node.proc.wait(timeout=60)
        code, out = node.stop()
        assert code == 2 and words in out, out
