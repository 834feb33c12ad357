"""The session's rules for the top drive, without ROS: the motor torque command and the
JointState command are accepted or refused (whole, with a reason naming what was wrong), and
the top drive's parameters reach the rig, a mode switch at run time included."""

from __future__ import annotations

import math

import pytest

from drill_sim.core import ParameterError, load_preset
from drill_sim.session import rules
from drill_sim.session.parameter_table import specs
from drill_sim.wire.cdr_decode import JointCommand


def _params(**changes) -> dict[str, object]:
    p = {s.name: s.default for s in specs(load_preset("base"))}
    p.update(changes)
    return p


def _rig(**changes):
    p = _params(**changes)
    rig = rules.make_rig(p)
    rules.start(rig, p)
    return rig, p


def _torque(value: float) -> tuple[float, ...]:
    return (0.0, 0.0, 0.0, 0.0, 0.0, value)


def test_parameters_make_the_preset_top_drive_with_zero_as_no_rate_limit():
    rig, p = _rig(top_drive_mode="torque", motor_torque_rate_nm_s=0.0)
    preset = load_preset("base").top_drive
    assert rig.top_drive.motor_torque_rate_nm_s == math.inf
    assert rig.top_drive.drive_kp_nm_s_rad == preset.drive_kp_nm_s_rad
    assert rig.top_drive.top_drive_mode == "torque"
    # a session recorded before the top drive's parameters: the seed's kinematic drive
    old = {k: v for k, v in p.items() if k not in rules.TOP_DRIVE_FIELDS}
    assert rules.top_drive_parameters(old).top_drive_mode == "kinematic"


def test_torque_command_only_in_torque_mode_and_finite():
    rig, p = _rig()
    what, _, expected = rules.apply_command(rig, p, "top_drive_torque", "",
                                                  _torque(5e3))
    assert "top_drive_mode is kinematic" in what and "top_drive_mode = torque" in expected
    rig, p = _rig(top_drive_mode="torque")
    held = rig.commanded_motor_torque_nm
    for bad in (math.nan, math.inf, -2e6):
        assert rules.apply_command(rig, p, "top_drive_torque", "", _torque(bad)) is not None
        assert rig.commanded_motor_torque_nm == held
    assert rules.apply_command(rig, p, "top_drive_torque", "top_drive", _torque(-5e3)) is None
    assert rig.commanded_motor_torque_nm == -5e3           # braking torques are commands too


@pytest.mark.parametrize("cmd, fragment", [
    (JointCommand(("top_drive", "crown_block"), (), (1.0, 1.0), ()), "one of 'top_drive'"),
    (JointCommand(("top_drive", "top_drive"), (), (1.0, 1.0), ()), "distinct joint names"),
    (JointCommand(("top_drive", "hook"), (), (1.0,), ()), "2 values, or none"),
    (JointCommand(("top_drive",), (0.5,), (), ()), "velocity (top_drive) and effort"),
    (JointCommand(("hook",), (), (1.0,), ()), "hook takes effort only"),
    (JointCommand(("top_drive",), (), (), ()), "a velocity or an effort"),
    (JointCommand(("top_drive", "hook"), (), (), (1e3, math.nan)), "a finite value in"),
    (JointCommand(("top_drive",), (), (99.0,), ()), "a finite value in [0, 30] rad/s"),
])
def test_a_bad_joint_command_is_refused_whole(cmd, fragment):
    rig, p = _rig(top_drive_mode="torque")
    before = (rig.commanded_speed_rad_s, rig.commanded_hook_load_n,
              rig.commanded_motor_torque_nm)
    refusal = rules.apply_command(rig, p, rules.JOINT_COMMANDS, "", cmd)
    assert refusal is not None and fragment in " ".join(map(str, refusal)), refusal
    assert (rig.commanded_speed_rad_s, rig.commanded_hook_load_n,
            rig.commanded_motor_torque_nm) == before


def test_a_joint_command_sets_speed_torque_and_hook_load():
    rig, p = _rig(top_drive_mode="torque")
    cmd = JointCommand(("hook", "top_drive"), (), (), (250e3, 7e3))
    assert rules.apply_command(rig, p, rules.JOINT_COMMANDS, "", cmd) is None
    assert (rig.commanded_hook_load_n, rig.commanded_motor_torque_nm) == (250e3, 7e3)
    cmd = JointCommand(("top_drive",), (), (4.0,), ())
    assert rules.apply_command(rig, p, rules.JOINT_COMMANDS, "", cmd) is None
    assert rig.commanded_speed_rad_s == 4.0


def test_a_mode_switch_at_run_time_is_bumpless_and_a_bad_change_leaves_the_rig():
    rig, p = _rig()
    rig.advance(1.0)
    torque = rig.sample().surface_torque_nm
    new = dict(p, top_drive_mode="torque")
    assert rules.apply_changes(rig, p, new) == {"top_drive_mode"}
    assert rig.commanded_motor_torque_nm == pytest.approx(torque, rel=1e-12)
    assert rig.sample().motor_torque_nm == pytest.approx(torque, rel=1e-12)
    # a change refused by the rig's parameters takes the top drive's change back with it
    with pytest.raises(ParameterError, match="blade_count"):
        rules.apply_changes(rig, new, dict(new, top_drive_mode="speed", blade_count=5))
    assert rig.top_drive.top_drive_mode == "torque"
