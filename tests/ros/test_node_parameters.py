"""The node's parameters: a bad value at start-up is one line and exit status 2, an integer
where a real number is expected works, run-time changes are refused with the reason when the
parameter cannot change or the value makes no sense, and msg_docs/node.md gives every
parameter's range as the table has it."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameters, SetParameters
from rosutil import NodeProcess, call_service, wait_for
from std_msgs.msg import Bool

from drill_sim.core import load_preset
from drill_sim.session.parameter_table import specs

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("param, fragment", [
    ("rate_hz:=-5.0", "rate_hz = -5.0: expected a finite number from 1 to 5000 Hz"),
    ("rate_hz:=abc", "rate_hz = 'abc'"),
    ("publish_clock:=1", "publish_clock = 1: expected true or false"),
    ("blade_count:=40", "blade_count = 40: expected a whole number from 2 to 12"),
    ("submerged_weight_n:=1e9", "the heaviest drill strings weigh 3-4 MN"),
    ("max_speed:=true", "max_speed = true needs publish_clock = true"),
    ("record_split_size_bytes:=1", "1 MiB at least"),
    ("record_split_duration_s:=0.001", "a file a second at least"),
    ("initial_weight_on_bit_n:=400000.0", "exceeds submerged_weight_n"),
    ("lockstep:=true", "lockstep = true needs publish_clock = true"),
    ("lockstep_topics:=[cmd/top_drive, cmd/nope]",
     "expected a list of one or more of cmd/top_drive"),
    ("lockstep_timeout_s:=nan", "lockstep_timeout_s = nan: expected a finite number"),
])
def test_a_bad_startup_parameter_is_one_line_and_status_2(ros, param, fragment):
    proc = NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/badparam", "-p", param)
    code = proc.proc.wait(timeout=60)
    out = proc.proc.stdout.read()
    lines = out.strip().splitlines()
    assert code == 2 and len(lines) == 1 and fragment in lines[0], out


def _value(value: object) -> ParameterValue:
    if isinstance(value, bool):
        return ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=value)
    if isinstance(value, int):
        return ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=value)
    return ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value)


def _set(ros, rig: str, name: str, value: object):
    request = SetParameters.Request(parameters=[Parameter(name=name, value=_value(value))])
    return call_service(ros, SetParameters, f"{rig}/set_parameters", request).results[0]


def _get(ros, rig: str, name: str) -> ParameterValue:
    return call_service(ros, GetParameters, f"{rig}/get_parameters",
                        GetParameters.Request(names=[name])).values[0]


def _running(ros, ns: str, *args: str) -> NodeProcess:
    proc = NodeProcess("drill_sim_node", "--ros-args", "-r", f"__ns:={ns}", *args)
    seen: list[bool] = []
    sub = ros.create_subscription(Bool, f"{ns}/drill_sim/bit/stick_slip", seen.append, 10)
    wait_for(lambda: len(seen) > 5 or proc.proc.poll() is not None, ros, 30.0, "the rig")
    ros.destroy_subscription(sub)
    assert proc.proc.poll() is None, proc.stop()[1]
    return proc


def test_integers_for_real_numbers_at_start_and_at_run_time(ros):
    rig = "/intparam/drill_sim"
    with _running(ros, "/intparam", "-p", "rate_hz:=500", "-p", "blade_count:=4.0"):
        rate = _get(ros, rig, "rate_hz")
        assert (rate.type, rate.double_value) == (ParameterType.PARAMETER_DOUBLE, 500.0)
        assert _get(ros, rig, "blade_count").integer_value == 4
        result = _set(ros, rig, "real_time_factor", 2)
        assert result.successful, result.reason
        assert _get(ros, rig, "real_time_factor").double_value == 2.0


def test_run_time_refusals_say_why(ros, tmp_path):
    rig = "/rtparam/drill_sim"
    with _running(ros, "/rtparam", "-p", f"record:={tmp_path / 'bag'}"):
        refused = {
            "publish_clock": (True, "chooses the node's time"),
            "max_speed": (True, "tick loop"),
            "blade_count": (6, "sector of the rock surface"),
            "record_split_duration_s": (0.001, "a file a second at least"),
            "record_split_size_bytes": (1000, "1 MiB at least"),
            "submerged_weight_n": (1e9, "3-4 MN"),
            "bha_mass_kg": (0.0, "from 300 to 200000 kg"),
            "initial_weight_on_bit_n": (5e5, "exceeds submerged_weight_n"),
            "rate_hz": (300.0, "whole number of the session's step"),
            "lockstep": (True, "tick loop"),
        }
        for name, (value, why) in refused.items():
            result = _set(ros, rig, name, value)
            assert not result.successful and why in result.reason, (name, result.reason)
        for name, value in (("record_split_size_bytes", 1 << 20), ("rate_hz", 500.0),
                            ("record_split_duration_s", 2), ("submerged_weight_n", 4e5)):
            result = _set(ros, rig, name, value)
            assert result.successful, (name, result.reason)
    with _running(ros, "/rtparam2"):
        result = _set(ros, "/rtparam2/drill_sim", "record_split_duration_s", 5.0)
        assert not result.successful and "does not record" in result.reason


def test_node_md_gives_every_parameter_its_range():
    text = (ROOT / "msg_docs" / "node.md").read_text()
    for spec in specs(load_preset("base")):
        row = re.search(rf"^\| `{spec.name}` \|.*$", text, re.M)
        assert row is not None, f"{spec.name} is not in msg_docs/node.md"
        if spec.low is not None:
            low = spec.low if spec.off_or_at_least is None else spec.off_or_at_least
            for bound in (low, spec.high):
                shown = {f"{bound:g}", str(int(bound))} if bound == int(bound) else {f"{bound:g}"}
                if spec.name == "record_split_size_bytes" and bound == spec.high:
                    shown = {"2^62"}
                assert any(b in row.group(0) for b in shown), (spec.name, bound, row.group(0))
        assert row.group(0).rstrip(" |").split("|")[-1].strip().startswith(
            "no" if spec.read_only else "yes"), row.group(0)
