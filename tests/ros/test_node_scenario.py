"""The installed node playing a scenario itself (``-p scenario:=FILE``): its parameter change
lands on the tick of its simulated time, whatever the wall clock did, and the recorded session
re-simulates exactly; a scenario the node cannot play stops it at start in one line."""

from __future__ import annotations

import json
import struct
import subprocess

import pytest
import yaml
from conftest import installed
from rosgraph_msgs.msg import Clock
from rosutil import NodeProcess, wait_for

from drill_sim.bag.bag import Bag

SCENARIO = {"description": "harder rock at 0.75 s", "initial_state": "steady",
            "duration_s": 2.0,
            "points": [{"at_s": 0.0, "rpm": 60.0, "wob_kn": 100.0},
                       {"at_s": 0.5, "rpm": 70.0}],
            "changes": [{"at_s": 0.75, "intrinsic_specific_energy_pa": 1.3e8}]}


def test_the_node_plays_a_scenario_on_its_own_clock(ros, tmp_path):
    path = tmp_path / "harder.yaml"
    path.write_text(yaml.safe_dump(SCENARIO))
    bag = tmp_path / "played"
    clock: list[float] = []
    ros.create_subscription(Clock, "/clock", lambda m: clock.append(
        m.clock.sec + 1e-9 * m.clock.nanosec), 10)
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/played", "-p",
                     f"scenario:={path}", "-p", f"record:={bag}", "-p", "publish_clock:=true",
                     "-p", "max_speed:=true", "-p", "rate_hz:=200.0") as node:
        wait_for(lambda: clock and clock[-1] > 1.5, ros, 60.0, "simulated time 1.5 s")
    code, out = node.stop()
    assert code == 0, out
    with Bag.open(bag) as b:
        events = [json.loads(m.data[8:8 + struct.unpack_from("<I", m.data, 4)[0] - 1])
                  for m in b.messages({"/played/drill_sim/events"}, [])]
    assert [e["event"] for e in events] == ["parameters"]
    assert events[0]["sim_time_s"] == pytest.approx(0.75, abs=1e-9)   # the tick of its time
    done = subprocess.run([installed("drill_sim"), "bag", "resim", str(bag), "--json"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    assert json.loads(done.stdout)["exact"] is True


def test_a_scenario_the_node_cannot_play_stops_it_in_one_line(tmp_path):
    """Refused before anything runs: one line, status 2, and no bag left behind."""
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(dict(SCENARIO, changes=[
        {"at_s": 0.5, "friction_coeficient": 0.5}])))
    bag = tmp_path / "never"
    done = subprocess.run([installed("drill_sim_node"), "--ros-args", "-p",
                           f"scenario:={path}", "-p", f"record:={bag}"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert "did you mean friction_coefficient" in done.stderr
    assert "Traceback" not in done.stderr and not bag.exists()
    done = subprocess.run([installed("drill_sim_node"), "--ros-args", "-p",
                           "scenario:=tag_bottom", "-p", "initial_state:=steady"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "expected -p initial_state:=rest" in done.stderr


def test_a_scenario_brings_its_initial_state(ros):
    """tag_bottom is written for a rig at rest: without -p initial_state the node takes it."""
    clock: list[float] = []
    ros.create_subscription(Clock, "/clock", lambda m: clock.append(
        m.clock.sec + 1e-9 * m.clock.nanosec), 10)
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/tag", "-p",
                     "scenario:=tag_bottom", "-p", "publish_clock:=true", "-p",
                     "max_speed:=true", "-p", "rate_hz:=100.0") as node:
        wait_for(lambda: clock and clock[-1] > 0.5, ros, 60.0, "simulated time 0.5 s")
    code, out = node.stop()
    assert code == 0, out
    assert "playing scenario 'tag_bottom'" in out
