"""The laws against hand computation: PI sums, anti-windup, bumpless start, SoftSpeed gains."""

from __future__ import annotations

import math

import pytest

from drill_sim.control import LAWS, PI, SoftSpeed, SurfaceMeasurement, make_law

Z = 302.0
J_TD = 2900.0
TORQUE_LAWS = ("stiff_pi", "soft_speed", "z_torque")


def m(speed: float, torque: float = 0.0, t: float = 0.0) -> SurfaceMeasurement:
    return SurfaceMeasurement(t, speed, torque, torque)


def test_registry_names():
    assert set(LAWS) == {"kinematic", "stiff_pi", "soft_speed", "z_torque", "off"}
    for name, cls in LAWS.items():
        assert cls.name == name
        assert cls.output_kind == ("speed" if name == "kinematic" else "torque")


def test_stiff_pi_defaults_and_integral_after_n_steps():
    law = make_law("stiff_pi", 0.01, Z, J_TD)
    assert law.pi.kp_nm_s_rad == pytest.approx(50 * Z)
    assert law.pi.ki_nm_rad == pytest.approx(5 * J_TD)
    law = make_law("stiff_pi", 0.01, Z, J_TD, kp_nm_s_rad=100.0, ki_nm_rad=10.0)
    law.reset(speed_set_rad_s=2.0)
    for n in range(1, 51):
        u = law.step(m(0.0))
        assert u == pytest.approx(100.0 * 2.0 + 10.0 * 0.01 * n * 2.0)   # K_p e + K_i n h e


@pytest.mark.parametrize("name", TORQUE_LAWS)
def test_output_leaves_the_limit_as_soon_as_the_error_changes_sign(name):
    """A windup integral would hold the output at the limit for many samples after the flip."""
    law = make_law(name, 0.01, Z, J_TD, torque_min_nm=-500.0, torque_max_nm=500.0)
    law.reset(speed_set_rad_s=5.0)
    law.bumpless_start(0.0, m(5.0))
    law.set_speed(5.2)                       # small error: the integral alone reaches the limit
    outputs = [law.step(m(5.0)) for _ in range(5000)]
    assert outputs[-1] == 500.0
    assert all(abs(u) <= 500.0 for u in outputs)
    # conditional integration: while saturated the integral q did not grow past what puts the
    # output on the limit (from 0 at the bumpless start: q <= max(0, 500 - K_p e)), so on the
    # flip to e = -0.01 the output drops at least K_p 0.01 below that; an integral merely
    # clamped to the limits (q = 500) would leave it within K_p 0.01 of the limit
    kp = law.pi.kp_nm_s_rad
    law.set_speed(4.99)                      # error -0.01 rad/s
    assert law.step(m(5.0)) <= max(0.0, 500.0 - kp * 0.2) - kp * 0.01 + 1e-6
    law.set_speed(100.0)                     # and the lower side
    assert law.step(m(5.0)) == 500.0


def test_pi_integral_frozen_in_saturation_by_hand():
    pi = PI(0.01, kp_nm_s_rad=100.0, ki_nm_rad=1000.0, torque_min_nm=-500.0,
            torque_max_nm=500.0)
    for _ in range(10_000):
        u = pi.output(0.2)                   # p = 20, q grows by 2 a step until u hits 500
    assert u == 500.0
    assert pi.q_nm == pytest.approx(480.0)   # frozen at the last admissible value, not 20 000
    assert pi.output(-0.01) == pytest.approx(-1.0 + 479.9)


@pytest.mark.parametrize("name", [*TORQUE_LAWS, "off"])
def test_bumpless_start_first_output_is_the_current_torque(name):
    law = make_law(name, 0.001, Z, J_TD)
    law.reset(speed_set_rad_s=7.0)
    first = law.bumpless_start(1234.5, m(6.5, torque=1234.5))
    assert first == pytest.approx(1234.5, rel=1e-12)
    second = law.step(m(6.5, torque=first, t=0.001))
    ki_h_e = law.pi.ki_nm_rad * 0.001 * 0.5 if name != "off" else 0.0
    assert second - first == pytest.approx(ki_h_e, abs=1e-9)   # only the integral moves on


def test_bumpless_start_outside_the_limits_gives_the_limit():
    law = make_law("stiff_pi", 0.01, Z, J_TD, torque_min_nm=0.0, torque_max_nm=1000.0)
    law.reset(1.0)
    assert law.bumpless_start(5000.0, m(1.0)) == 1000.0


def test_kinematic_passes_the_speed_set_point():
    law = make_law("kinematic", 0.01, Z, J_TD)
    law.reset(speed_set_rad_s=6.0)
    assert law.step(m(1.0)) == 6.0
    assert law.bumpless_start(3.0, m(3.0)) == 3.0     # adopts the speed it takes over from
    assert law.step(m(2.0)) == 3.0


def test_soft_speed_gains_and_inertia_compensation():
    f_t, j_c = 0.5, 1000.0
    law = make_law("soft_speed", 0.001, Z, J_TD, kp_over_impedance=3.0,
                   tuning_frequency_hz=f_t, compensated_inertia_kg_m2=j_c)
    assert law.pi.kp_nm_s_rad == pytest.approx(3.0 * Z)
    assert law.pi.ki_nm_rad == pytest.approx((2 * math.pi * f_t) ** 2 * (J_TD - j_c))
    plain = SoftSpeed(0.001, Z, J_TD, kp_over_impedance=3.0, tuning_frequency_hz=f_t)
    plain.pi.ki_nm_rad = law.pi.ki_nm_rad            # same PI, only J_c differs
    for law_ in (law, plain):
        law_.reset(0.0)
        law_.bumpless_start(0.0, m(0.0))
    slope = 2.0                                      # rad/s², a constant acceleration
    for k in range(1, 2001):
        speed = slope * k * 0.001
        diff = law.step(m(speed)) - plain.step(m(speed))
    # Same error history, so the difference is J_c times the filtered derivative (settled).
    assert diff == pytest.approx(j_c * slope, rel=1e-3)


def test_z_torque_without_oscillation_is_the_stiff_pi():
    """Constant torque and speed: T̃ = 0 after the HPF, so the error is Ω_set - Ω."""
    z = make_law("z_torque", 0.01, Z, J_TD, kp_nm_s_rad=100.0, ki_nm_rad=10.0)
    s = make_law("stiff_pi", 0.01, Z, J_TD, kp_nm_s_rad=100.0, ki_nm_rad=10.0)
    for law in (z, s):
        law.reset(3.0)
        law.bumpless_start(800.0, m(2.0, torque=800.0))
    for _ in range(100):
        assert z.step(m(2.0, torque=800.0)) == pytest.approx(s.step(m(2.0, torque=800.0)))
    assert z.torque_feedback_nm == pytest.approx(0.0, abs=1e-9)
