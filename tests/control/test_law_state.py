"""A law's state as built and as reset: at rest it commands nothing, a reset forgets all of its
history, and every gain left out takes its documented default on the law that runs (not only
in the signature)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drill_sim.control import PI, SurfaceMeasurement, make_law
from drill_sim.control.filters import FilteredDerivative, FirstOrderSection, HeldLag, SampleWindow

H, Z, J = 0.01, 302.4, 2900.0
LAWS = ("stiff_pi", "soft_speed", "z_torque", "off", "kinematic")
AT_REST = SurfaceMeasurement(0.0, 0.0, 0.0, 0.0)


def _history(law, seed: int) -> None:
    """Some seconds of an oscillating top drive, to fill every filter and the integral."""
    rng = np.random.default_rng(seed)
    law.set_speed(6.0)
    for k in range(300):
        speed = 6.0 + 3.0 * math.sin(0.3 * k) + rng.normal(0.0, 0.2)
        torque = 8000.0 + 4000.0 * math.cos(0.3 * k)
        law.step(SurfaceMeasurement(k * H, speed, torque, torque))


@pytest.mark.parametrize("name", LAWS)
def test_a_new_law_at_rest_commands_nothing(name):
    """Built and stepped at rest (set-point 0, speed 0, torque 0): every output is exactly 0,
    so no filter, window, lag or integral starts from anything but rest."""
    law = make_law(name, H, Z, J, **({"compensated_inertia_kg_m2": 2000.0}
                                      if name == "soft_speed" else {}))
    assert law.speed_set_rad_s == 0.0
    assert [law.step(AT_REST) for _ in range(50)] == [0.0] * 50


@pytest.mark.parametrize("name", LAWS)
def test_a_reset_forgets_the_history(name):
    """After any history, reset(Ω) leaves the law as a new one reset(Ω): the same inputs then
    give the same outputs, to the last bit (Z-Torque with both signal lags, held signals, and
    its saturation regulator backed off by a history on its limits)."""
    gains = {"soft_speed": {"compensated_inertia_kg_m2": 2000.0},
             "z_torque": {"torque_signal_tau_s": 0.05, "speed_signal_tau_s": 0.02,
                          "measurement_period_s": 0.03, "backoff_per_s": 5.0,
                          "torque_min_nm": -2000.0, "torque_max_nm": 2000.0}}.get(name, {})
    used, new = make_law(name, H, Z, J, **gains), make_law(name, H, Z, J, **gains)
    _history(used, 1)
    if name == "z_torque":                      # the history backed the regulator's α off
        assert used.alpha_in_use < used.alpha
    used.reset(4.0)
    new.reset(4.0)
    inputs = [SurfaceMeasurement(k * H, 4.0 + 0.5 * math.sin(0.2 * k), 3000.0 + 100.0 * k,
                                 3000.0) for k in range(100)]
    assert [used.step(m) for m in inputs] == [new.step(m) for m in inputs]
    at_rest = make_law(name, H, Z, J, **gains)
    at_rest.reset(0.0)
    assert [at_rest.step(AT_REST) for _ in range(20)] == [0.0] * 20


def test_z_torques_estimates_start_and_settle_at_what_they_mean():
    """T̂_p and T̃ of "the last step": 0 before any; after a bumpless start on a steady drive
    applying T, T̂_p = T (the pipe carries what the motor applies) and T̃ = 0 (no
    oscillation)."""
    law = make_law("z_torque", H, Z, J)
    assert (law.pipe_torque_estimate_nm, law.torque_feedback_nm) == (0.0, 0.0)
    law.reset(6.0)
    law.bumpless_start(9000.0, SurfaceMeasurement(0.0, 6.0, 9000.0, 9000.0))
    assert law.pipe_torque_estimate_nm == pytest.approx(9000.0, rel=1e-12)
    assert law.torque_feedback_nm == pytest.approx(0.0, abs=1e-9)


# the law that runs, gain by gain, with nothing given (msg_docs/control.md's defaults)
BUILT = {
    "stiff_pi": {"pi.kp_nm_s_rad": 50 * Z, "pi.ki_nm_rad": 5 * J,
                 "pi.torque_min_nm": -1e5, "pi.torque_max_nm": 1e5},
    "soft_speed": {"pi.kp_nm_s_rad": 4 * Z, "pi.ki_nm_rad": (2 * math.pi * 0.2) ** 2 * J,
                   "tuning_frequency_hz": 0.2, "compensated_inertia_kg_m2": 0.0,
                   "derivative.corner_hz": 5.0},
    "z_torque": {"alpha": 0.25, "pi.kp_nm_s_rad": 50 * Z, "pi.ki_nm_rad": 5 * J,
                 "lowpass_speed.corner_hz": 10.0, "lowpass_torque.corner_hz": 2.5,
                 "lowpass_out.corner_hz": 2.5, "highpass.corner_hz": 0.05,
                 "measurement_period_s": H, "torque_window.n": 1, "speed_lag.tau_s": 0.0,
                 "torque_lag.tau_s": 0.0},
}


@pytest.mark.parametrize("name", list(BUILT))
def test_the_running_law_has_the_documented_defaults(name):
    law = make_law(name, H, Z, J)
    for path, expected in BUILT[name].items():
        value = law
        for part in path.split("."):
            value = getattr(value, part)
        assert value == pytest.approx(expected, rel=1e-12), path


def test_z_torques_measurement_period_is_whole_samples():
    """A period is rounded to whole samples (0.034 s at 10 ms: 3); the lags are each other's."""
    law = make_law("z_torque", H, Z, J, measurement_period_s=0.034, torque_signal_tau_s=0.2,
                   speed_signal_tau_s=0.05)
    assert law.measurement_period_s == pytest.approx(0.03, rel=1e-12)
    assert (law.torque_window.n, law.speed_window.n) == (3, 3)
    assert (law.speed_lag.tau_s, law.torque_lag.tau_s) == (0.2, 0.05)
    assert make_law("z_torque", H, Z, J, measurement_period_s=0.004).measurement_period_s == H


def test_the_pi_recovers_from_the_lower_limit_under_a_negative_feed_forward():
    """Conditional integration holds q only while the error pushes into the limit: with the
    output on the lower limit because of a feed-forward (SoftSpeed's inertia torque), a
    positive error still integrates (q grows by K_i h e)."""
    pi = PI(0.01, kp_nm_s_rad=100.0, ki_nm_rad=1000.0, torque_min_nm=-500.0,
            torque_max_nm=500.0)
    assert pi.output(0.5, -2000.0) == -500.0
    assert pi.q_nm == pytest.approx(1000.0 * 0.01 * 0.5, rel=1e-12)
    assert pi.output(0.5, -2000.0) == -500.0
    assert pi.q_nm == pytest.approx(2 * 1000.0 * 0.01 * 0.5, rel=1e-12)


def test_the_pi_winds_only_onto_the_lower_limit():
    """The mirror of test_pi_integral_frozen_in_saturation_by_hand: q stops at what puts the
    output on the lower limit, so a small positive error leaves it at once."""
    pi = PI(0.01, kp_nm_s_rad=100.0, ki_nm_rad=1000.0, torque_min_nm=-500.0,
            torque_max_nm=500.0)
    for _ in range(10_000):
        u = pi.output(-0.2)
    assert u == -500.0
    assert pi.q_nm == pytest.approx(-480.0)
    assert pi.output(0.01) == pytest.approx(1.0 - 479.9)


def test_filters_start_at_rest_and_settle_where_told():
    section = FirstOrderSection(2.0, H)
    assert (section.x1, section.y1) == (0.0, 0.0)
    lag = HeldLag(0.1, H)
    assert (lag.x1, lag.y1) == (0.0, 0.0)
    assert lag.step(0.0) == 0.0
    assert HeldLag(0.0, H).step(3.0) == 3.0                 # no lag: the sample itself
    window = SampleWindow(5)
    assert (window.ring, window.i, window.total) == ([0.0] * 5, 0, 0.0)
    assert window.mean() == 0.0
    window.settle(7.0)
    assert window.mean() == pytest.approx(7.0, rel=1e-15)
    assert window.push(7.0) == 7.0
    derivative = FilteredDerivative(5.0, H)
    derivative.settle(4.0)
    assert derivative.step(4.0) == 0.0


def test_a_reset_z_torque_has_no_estimate_and_a_start_takes_any_sign():
    """After a reset T̂_p and T̃ are 0 again (no step since); a bumpless start takes a top
    drive turning backwards (backspin) and a negative motor torque, as Off does."""
    law = make_law("z_torque", H, Z, J)
    _history(law, 2)
    assert law.pipe_torque_estimate_nm != 0.0
    law.reset(3.0)
    assert (law.pipe_torque_estimate_nm, law.torque_feedback_nm) == (0.0, 0.0)
    backwards = SurfaceMeasurement(0.0, -1.5, -2000.0, -2000.0)
    assert math.isfinite(law.bumpless_start(-2000.0, backwards))
    off = make_law("off", H, Z, J)
    assert off.bumpless_start(-2000.0, backwards) == -2000.0
    assert off.step(AT_REST) == -2000.0


def test_a_supervisor_runs_a_law_without_limits():
    """``off`` has no PI and no limits: the supervisor steps it, counts its samples and
    counts nothing as saturated."""
    from drill_sim.control.supervisor import Supervisor
    sup = Supervisor(H, Z, J, "off")
    assert sup.step(SurfaceMeasurement(0.0, 1.0, 700.0, 700.0)) == 700.0     # takes over
    assert sup.step(SurfaceMeasurement(0.01, 1.0, 900.0, 900.0)) == 700.0    # and holds it
    assert sup.take_window() == {"samples": 2, "saturation_fraction": 0.0,
                                 "windup_fraction": 0.0}
