"""``drill_sim_controller`` against the installed rig node, through the rig's topics only: it
answers each sample with a torque command stamped with that sample's stamp, takes over the
drive without a bump (the rig's drive mode switched for it), refuses bad gains naming them,
and reports law, saturation and wind-up on /diagnostics."""

from __future__ import annotations

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameters, SetParameters
from rosutil import NodeProcess, call_service, set_double, wait_for

NS = "/ctl"
RIG = f"{NS}/drill_sim"


def _stamp(msg) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def _set(ros, target: str, name: str, value: ParameterValue):
    return call_service(ros, SetParameters, f"{target}/set_parameters", SetParameters.Request(
        parameters=[Parameter(name=name, value=value)])).results[0]


def _mode(ros) -> str:
    r = call_service(ros, GetParameters, f"{RIG}/get_parameters",
                     GetParameters.Request(names=["top_drive_mode"]))
    return r.values[0].string_value


def test_controller_takes_over_bumplessly_answers_each_sample_and_reports(ros):
    motor: list[tuple[int, float]] = []          # (stamp [ns], motor torque applied [N m])
    commands: list[tuple[int, float]] = []       # the controller's (stamp [ns], torque [N m])
    diagnostics: list = []
    ros.create_subscription(WrenchStamped, f"{RIG}/top_drive/motor_wrench",
                            lambda m: motor.append((_stamp(m), m.wrench.torque.z)), 10000)
    ros.create_subscription(WrenchStamped, f"{RIG}/cmd/top_drive_torque",
                            lambda m: commands.append((_stamp(m), m.wrench.torque.z)), 10000)
    ros.create_subscription(DiagnosticArray, "/diagnostics", lambda m: diagnostics.extend(
        s for s in m.status if "controller" in s.name), 100)
    with NodeProcess("drill_sim_node", "--ros-args", "-r", f"__ns:={NS}",
                     "-p", "top_drive_mode:=speed", "-p", "rate_hz:=250.0"), \
         NodeProcess("drill_sim_controller", "--ros-args", "-r", f"__ns:={NS}",
                     "-p", f"rig:={RIG}", "-p", "enabled:=false", "-p", "sample_period_s:=0",
                     "-p", "manage_drive_mode:=true", "-p", "inputs:=exact") as ctl:
        controller = f"{NS}/drill_sim_controller"
        wait_for(lambda: len(motor) > 200, ros, 30.0, "the rig running")
        wait_for(lambda: any(s.message.endswith("disabled") for s in diagnostics), ros, 30.0,
                 "the controller's diagnostics")
        assert not commands                                  # disabled: silent
        assert _mode(ros) == "speed"
        before = motor[-1][1]
        on = _set(ros, controller, "enabled",
                  ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=True))
        assert on.successful, on.reason
        wait_for(lambda: len(commands) > 300, ros, 30.0, "torque commands")
        assert _mode(ros) == "torque"
        # bumpless: its first command is the torque the drive was applying, near the last seen
        assert abs(commands[0][1] - before) < 0.05 * abs(before) + 200.0
        # every command answers a sample: its stamp is one the rig published
        published = {s for s, _ in motor}
        assert all(s in published for s, _ in commands[:-5])
        bad = set_double(ros, controller, "z_torque.alpha", float("nan"))
        assert not bad.successful and "alpha" in bad.reason
        bad = _set(ros, controller, "law",
                   ParameterValue(type=ParameterType.PARAMETER_STRING, string_value="pid"))
        assert not bad.successful and "pid" in bad.reason
        ok = set_double(ros, controller, "z_torque.alpha", 0.5)
        assert ok.successful, ok.reason
        # a law that is not on: its gains are checked when set, not when it is switched on
        bad = set_double(ros, controller, "soft_speed.tuning_frequency_hz", float("nan"))
        assert not bad.successful and "tuning_frequency_hz = nan" in bad.reason, bad.reason
        bad = set_double(ros, controller, "stiff_pi.kp_nm_s_rad", -1.0)
        assert not bad.successful and "kp_nm_s_rad" in bad.reason, bad.reason
        # an integer where a real is expected, as the rig takes it
        one = _set(ros, controller, "z_torque.alpha",
                   ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=1))
        assert one.successful, one.reason
        words = _set(ros, controller, "z_torque.alpha",
                     ParameterValue(type=ParameterType.PARAMETER_STRING, string_value="high"))
        assert not words.successful and "expected a number" in words.reason
        diagnostics.clear()
        wait_for(lambda: any(s.message == "z_torque: controlling" for s in diagnostics), ros,
                 30.0, "diagnostics while controlling")
        values = {v.key: v.value for v in diagnostics[-1].values}
        assert {"law", "saturation_fraction", "windup_fraction", "samples"} <= set(values)
        assert float(values["alpha_in_use"]) == 1.0      # z_torque.alpha as set, regulator off
        assert float(values["sample_period_s"]) == 1 / 250    # read from the rig's rate_hz
        off = _set(ros, controller, "enabled",
                   ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=False))
        assert off.successful
        wait_for(lambda: _mode(ros) == "speed", ros, 10.0, "the drive back on its own loop")
        # stopped while in charge, it hands the drive back rather than leave the last torque
        # command applied with nobody closing the loop
        on = _set(ros, controller, "enabled",
                  ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=True))
        assert on.successful, on.reason
        wait_for(lambda: _mode(ros) == "torque", ros, 10.0, "torque mode again")
        code, out = ctl.stop()
        assert code == 0, out
        assert _mode(ros) == "speed", out
        assert "back on its speed loop" in out, out


@pytest.mark.parametrize("program, args, fragment", [
    ("drill_sim_controller", ("-p", "law:=nosuch"), "law = 'nosuch': expected one of stiff_pi"),
    ("drill_sim_controller", ("-p", "enabled:=maybe"), "expecting type 'BOOL'"),
    ("drill_sim_controller", ("-p", "sample_period_s:=-0.001"),
     "sample_period_s = -0.001: expected 0 (the rig's 1/rate_hz"),
    ("drill_sim_controller", ("-p", "z_torque.measurement_period_s:=2.0"),
     "measurement_period_s = 2.0 is out of range"),
    ("drill_sim_controller", ("-p", "law:=stiff_pi", "-p", "z_torque.alpha:=-1.0"),
     "alpha = -1.0"),                         # a law that is not on is checked all the same
    ("drill_sim_controller", ("-p", "law:=policy"),
     "law = policy needs policy = package.module:callable"),
    ("drill_sim_controller", ("-p", "law:=policy", "-p", "policy:=no_such_mod:f"),
     "policy = 'no_such_mod:f': cannot import no_such_mod"),
    ("drill_sim_controller", ("-p", "sample_period_s:=abc"),
     "sample_period_s = 'abc': expected a number"),
    ("drill_sim_controller", ("--params-file", "nosuch.yaml"),
     "cannot start ROS: --params-file nosuch.yaml: no such file; expected the path of a YAML"),
    ("drill_sim_node", ("--params-file", "nosuch.yaml"),
     "cannot start ROS: --params-file nosuch.yaml: no such file"),
    ("drill_sim_node", ("--params-file", "/"), "--params-file /: not a file"),
])
def test_bad_start_is_a_clear_line_and_status_2(program, args, fragment):
    """A bad law, a value of the wrong type or a params file that is not there: the reason in
    one line of ours (rcl may log its own before it), exit status 2, no traceback."""
    proc = NodeProcess(program, "--ros-args", *args)
    code = proc.proc.wait(timeout=60)
    out = proc.proc.stdout.read()
    assert code == 2 and fragment in out and "Traceback" not in out, out
