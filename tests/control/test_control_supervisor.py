"""The law in service (drill_sim.control.supervisor): enable, switch and re-tune without a bump,
bad gains refused with the old law kept, saturation and wind-up counted."""

from __future__ import annotations

import math

import pytest

from drill_sim.control import ParameterError, SurfaceMeasurement
from drill_sim.control.supervisor import Supervisor

H, Z, J = 1e-3, 302.4, 2900.0
SPEED = 2 * math.pi


def m(t: float, speed: float = SPEED, motor: float = 5000.0) -> SurfaceMeasurement:
    return SurfaceMeasurement(t, speed, motor, motor)


def test_enabling_takes_over_from_the_torque_the_drive_applies():
    s = Supervisor(H, Z, J, "z_torque", enabled=False, speed_set_rad_s=SPEED)
    assert s.step(m(0.0)) is None
    s.set_enabled(True)
    assert s.step(m(0.001, speed=SPEED - 0.01, motor=4321.0)) == pytest.approx(4321.0)
    second = s.step(m(0.002, speed=SPEED - 0.01, motor=4321.0))
    assert abs(second - 4321.0) < 50.0 * Z * 0.02          # a small, not a step, change


def test_a_new_law_or_new_gains_continue_from_the_last_output():
    s = Supervisor(H, Z, J, "stiff_pi", speed_set_rad_s=SPEED)
    out = s.step(m(0.0, motor=5000.0))
    for k in range(1, 50):
        out = s.step(m(k * H, speed=SPEED - 0.05))
    assert abs(out - 5000.0) > 100.0             # the old law has moved well away from its start
    s.replace_law("soft_speed", {"tuning_frequency_hz": 0.76})
    assert s.step(m(0.05, speed=SPEED - 0.05)) == pytest.approx(out, rel=1e-9)
    before = s.last_output                        # taken before the step, not after it
    s.replace_law("soft_speed", {"tuning_frequency_hz": 0.5, "kp_over_impedance": 2.0})
    assert s.step(m(0.051, speed=SPEED - 0.05)) == pytest.approx(before, rel=1e-9)
    # a cold start of the same law from the same measurement lands far from it
    cold = Supervisor(H, Z, J, "soft_speed", {"tuning_frequency_hz": 0.5,
                                              "kp_over_impedance": 2.0},
                      speed_set_rad_s=SPEED)
    cold._started = True
    assert abs(cold.step(m(0.051, speed=SPEED - 0.05)) - before) > 100.0


def test_bad_gains_are_refused_and_the_law_kept():
    s = Supervisor(H, Z, J, "z_torque", speed_set_rad_s=SPEED)
    law = s.law
    with pytest.raises(ParameterError, match="alpha"):
        s.replace_law("z_torque", {"alpha": math.nan})
    with pytest.raises(ParameterError, match="highpass_hz"):
        s.replace_law("z_torque", {"highpass_hz": 5.0, "torque_lowpass_hz": 2.5})
    with pytest.raises(ParameterError, match="kinematic"):
        s.replace_law("kinematic", {})
    assert s.law is law


def test_saturation_and_windup_are_counted():
    s = Supervisor(H, Z, J, "stiff_pi", {"torque_min_nm": -1000.0, "torque_max_nm": 1000.0},
                   speed_set_rad_s=SPEED)
    for k in range(1000):            # 1 rad/s short of the set-point for a second
        s.step(m(k * H, speed=SPEED - 1.0, motor=1000.0))
    w = s.take_window()
    assert w["samples"] == 1000
    assert w["saturation_fraction"] == 1.0       # 50 Z * 1 rad/s = 15 kN·m > 1 kN·m
    assert w["windup_fraction"] == 1.0           # the integral held on a limit by the clamp
    assert s.take_window()["samples"] == 0
    # nothing wound up: the bumpless start put the integral at -1000 N·m (what K_p 1 rad/s of
    # error needs to give 1000), and conditional integration held it there while saturated;
    # so on the first sample the error reverses the output goes straight to the other limit,
    # where an integral merely clamped (grown to +1000) would give 1000 - K_p 0.01 = 849
    assert s.step(m(1.0, speed=SPEED + 0.01, motor=1000.0)) == -1000.0


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_both_limits_count_as_saturated_and_wound_up(sign):
    """Above the set-point the output sits on the lower limit and the integral on the upper
    one; below, the other way round: each limit counts, once a sample."""
    s = Supervisor(H, Z, J, "stiff_pi", {"torque_min_nm": -1000.0, "torque_max_nm": 1000.0},
                   speed_set_rad_s=SPEED)
    for k in range(100):
        out = s.step(m(k * H, speed=SPEED - sign, motor=sign * 1000.0))
    assert out == sign * 1000.0 and s.law.pi.q_nm == -sign * 1000.0
    assert s.take_window() == {"samples": 100, "saturation_fraction": 1.0,
                               "windup_fraction": 1.0}


def test_an_output_inside_the_limits_is_neither_saturated_nor_wound_up():
    s = Supervisor(H, Z, J, "stiff_pi", {"torque_min_nm": -9e4, "torque_max_nm": 1e5},
                   speed_set_rad_s=SPEED)
    for k in range(100):
        s.step(m(k * H, speed=SPEED - 0.01))
    assert s.take_window() == {"samples": 100, "saturation_fraction": 0.0,
                               "windup_fraction": 0.0}
    assert s.take_window() == {"samples": 0, "saturation_fraction": 0.0,
                               "windup_fraction": 0.0}


def test_a_law_without_limits_counts_nothing():
    """``off`` holds the torque it was handed: no limits, nothing saturates."""
    s = Supervisor(H, Z, J, "off", speed_set_rad_s=SPEED)
    assert s.limits() is None
    assert s.step(m(0.0, motor=1234.0)) == 1234.0
    assert s.take_window()["saturation_fraction"] == 0.0


def test_the_defaults_and_the_law_built_from_z_and_j():
    """Default law z_torque at rest (set-point 0); the law is built with this Z and J_TD (K_p
    and K_i default to them), not the defaults'."""
    s = Supervisor(H, Z, 1000.0)
    assert s.law.name == "z_torque" and s.speed_set_rad_s == 0.0
    assert s.law.pi.kp_nm_s_rad == pytest.approx(50.0 * Z, rel=1e-12)     # K_p = 50 Z
    assert s.law.pi.ki_nm_rad == 5.0 * 1000.0                              # K_i = 5 J_TD
    assert s.law.impedance_nm_s_rad == Z and s.law.top_drive_inertia_kg_m2 == 1000.0


def test_a_set_point_may_be_negative_but_must_be_a_number():
    s = Supervisor(H, Z, J, "stiff_pi", speed_set_rad_s=-1.0)
    s.set_speed(-2.0)                                       # turning backwards: allowed
    assert s.speed_set_rad_s == -2.0
    for bad in (math.nan, math.inf):
        with pytest.raises(ParameterError, match="speed_set_rad_s"):
            s.set_speed(bad)
        with pytest.raises(ParameterError, match="speed_set_rad_s"):
            Supervisor(H, Z, J, "stiff_pi", speed_set_rad_s=bad)


def test_a_speed_pass_through_is_refused_naming_the_torque_laws():
    with pytest.raises(ParameterError, match=r"expected one of stiff_pi, soft_speed, "
                                             r"z_torque, off$"):
        Supervisor(H, Z, J, "kinematic")


def test_enabling_again_while_enabled_changes_nothing():
    """set_enabled(True) on a running law is no take-over: the outputs are those of a law
    left alone (a restart would jump back to the last output)."""
    a = Supervisor(H, Z, J, "z_torque", speed_set_rad_s=SPEED)
    b = Supervisor(H, Z, J, "z_torque", speed_set_rad_s=SPEED)
    for k in range(50):
        meas = m(k * H, speed=SPEED - 0.2 * math.sin(k / 5.0))
        if k == 20:
            b.set_enabled(True)
        assert a.step(meas) == b.step(meas)
