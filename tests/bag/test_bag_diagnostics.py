"""``drill_sim bag diagnostics`` on a bag of DiagnosticArray messages serialized by rclpy (an
encoder independent of the decoder under test), run as a user runs it."""

from __future__ import annotations

import json
import subprocess

import pytest
from conftest import installed
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.serialization import serialize_message

from drill_sim.bag.writer import BagWriter

pytestmark = pytest.mark.offline        # its programs start no node

T0_NS = 1_700_000_000_000_000_000
TYPE = "diagnostic_msgs/msg/DiagnosticArray"


def _array(k: int) -> bytes:
    rig = DiagnosticStatus(level=bytes([1 if k == 2 else 0]), name="drill_sim: rig",
                           message=f"window {k}", hardware_id="base",
                           values=[KeyValue(key="overruns", value=str(3 * k)),
                                   KeyValue(key="sim_time_s", value=f"{k:.3f}")])
    other = DiagnosticStatus(level=bytes([2]), name="drill_sim_controller: law",
                             message="saturated", values=[KeyValue(key="u", value="ü")])
    a = DiagnosticArray(status=[rig, other])
    a.header.stamp.sec, a.header.frame_id = 1000 + k, "x" * k   # frame_id lengths vary
    return serialize_message(a)


def _bag(path, corrupt: bool = False):
    with BagWriter(path) as w:
        w.add_topic("/diagnostics", TYPE)
        w.add_topic("/drill_sim/bit/stick_slip", "std_msgs/msg/Bool")
        for k in range(4):
            data = _array(k)
            if corrupt and k == 1:
                data = data[:30]                       # cut short
            w.write("/diagnostics", data, T0_NS + k * 1_000_000_000)
    return path


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([installed("drill_sim"), "bag", "diagnostics", *args],
                          capture_output=True, text=True, timeout=60)


def test_statuses_rows_keys_and_levels(tmp_path):
    bag = _bag(tmp_path / "d")
    proc = _run(str(bag), "--name", "rig", "--keys", "overruns,sim_time_s,overrun")
    assert proc.returncode == 2, proc.stderr               # a key no status has: said so
    assert "no status shown has a value 'overrun' (did you mean 'overruns'?)" in proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0].split("\t") == ["t_s", "level", "name", "message", "overruns",
                                    "sim_time_s", "overrun"]
    rows = [line.split("\t") for line in lines[1:5]]
    assert [r[0] for r in rows] == ["0.000", "1.000", "2.000", "3.000"]   # log time from first
    assert [r[1] for r in rows] == ["OK", "OK", "WARN", "OK"]
    assert [r[4] for r in rows] == ["0", "3", "6", "9"] and {r[6] for r in rows} == {"-"}
    assert "4 statuses" in proc.stdout and "sim_time_s" in lines[-1]     # the last's keys
    assert _run(str(bag), "--name", "rig", "--keys", "overruns").returncode == 0
    every = [json.loads(line) for line in _run(str(bag), "--json").stdout.splitlines()]
    assert len(every) == 8 and every[1]["level"] == "ERROR" and every[1]["values"] == {"u": "ü"}
    assert every[6]["stamp_s"] == 1003.0 and every[6]["hardware_id"] == "base"


def test_a_damaged_message_is_reported_and_a_wrong_topic_refused(tmp_path):
    bag = _bag(tmp_path / "d", corrupt=True)
    proc = _run(str(bag), "--name", "rig")
    assert proc.returncode == 1
    assert "3 statuses" in proc.stdout
    assert proc.stderr.count("cannot hold this DiagnosticArray") == 1     # once, on stderr
    proc = _run(str(bag), "--json")                        # stdout stays JSON lines
    assert proc.returncode == 1 and all(json.loads(line) for line in proc.stdout.splitlines())
    assert "problem:" in proc.stderr
    for topic, expected in (("/nope", "has no topic /nope: expected one of its " + TYPE),
                            ("/drill_sim/bit/stick_slip", "is std_msgs/msg/Bool")):
        proc = _run(str(bag), "--topic", topic)
        assert proc.returncode == 2 and expected in proc.stderr, proc.stderr
        assert "Traceback" not in proc.stderr
