"""Filters, tuning helpers and gain validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drill_sim.control import (
    FilteredDerivative,
    FirstOrderSection,
    ParameterError,
    auto_tune_soft_speed,
    dominant_frequency_hz,
    first_mode_frequency_hz,
    make_law,
    pipe_impedance,
)
from drill_sim.core import load_preset


def _gain(section, f_hz: float, h_s: float) -> float:
    """Steady-state amplitude ratio for a sine, measured by running the filter on it."""
    n = round(40.0 / (f_hz * h_s))                 # 40 periods; the last 20 are measured
    t = np.arange(n) * h_s
    y = np.array([section.step(math.sin(2 * math.pi * f_hz * tk)) for tk in t])
    tail = slice(n // 2, n)
    basis = np.column_stack([np.sin(2 * math.pi * f_hz * t[tail]),
                             np.cos(2 * math.pi * f_hz * t[tail])])
    coef = np.linalg.lstsq(basis, y[tail], rcond=None)[0]
    return float(np.hypot(*coef))


@pytest.mark.parametrize("h_s", [0.01, 0.001])
@pytest.mark.parametrize(("corner_hz", "highpass"), [(2.5, False), (10.0, False), (0.5, True)])
def test_corner_gain_is_one_over_root_two(h_s, corner_hz, highpass):
    section = FirstOrderSection(corner_hz, h_s, highpass=highpass)
    assert _gain(section, corner_hz, h_s) == pytest.approx(1 / math.sqrt(2), rel=0.01)
    far = corner_hz / 20 if not highpass else corner_hz * 20   # pass band
    assert _gain(FirstOrderSection(corner_hz, h_s, highpass=highpass), far, h_s) == \
        pytest.approx(1.0, rel=0.01)


@pytest.mark.parametrize("h_s", [0.01, 0.001])
def test_filtered_derivative_is_a_derivative_below_its_corner(h_s):
    f_hz = 0.2
    gain = _gain(FilteredDerivative(5.0, h_s), f_hz, h_s)
    assert gain == pytest.approx(2 * math.pi * f_hz / math.hypot(1, f_hz / 5.0), rel=0.01)


def test_base_pipe_impedance_is_302():
    base = load_preset("base")
    assert pipe_impedance(base) == pytest.approx(302.0, rel=0.005)
    assert pipe_impedance("base") == pipe_impedance(base.string)


def test_first_mode_frequency_from_the_lumped_parameters():
    rig = load_preset("base").rig
    c, i = rig.torsional_stiffness_nm_per_rad, rig.bha_inertia_kg_m2
    assert first_mode_frequency_hz(rig) == pytest.approx(math.sqrt(c / i) / (2 * math.pi))
    assert first_mode_frequency_hz("base", 2900.0) == pytest.approx(
        math.sqrt(c * (1 / i + 1 / 2900.0)) / (2 * math.pi))


def _shaft_with_end_inertias_hz(geometry, top_kg_m2: float, bottom_kg_m2: float) -> float:
    """Lowest mode of a uniform shaft between two rigid inertias, from its closed-form
    frequency equation (θ = ωL/c, μ = end inertia / shaft inertia ρ J_p L):
    (θ² μ_top μ_bottom - 1) sin θ = θ (μ_top + μ_bottom) cos θ; a held top is μ_top → ∞,
    θ tan θ = 1/μ_bottom. Solved by bisection on its first sign change."""
    jp = math.pi / 32 * (geometry.pipe_od_m**4 - geometry.pipe_id_m**4)
    shaft = geometry.steel_density_kg_m3 * jp * geometry.pipe_length_m
    mb = bottom_kg_m2 / shaft
    if math.isinf(top_kg_m2):
        def f(x):
            return x * math.sin(x) - math.cos(x) / mb
    else:
        mt = top_kg_m2 / shaft
        def f(x):
            return (x * x * mt * mb - 1) * math.sin(x) - x * (mt + mb) * math.cos(x)
    lo, step = 1e-6, 1e-3
    while f(lo) * f(lo + step) > 0:
        lo += step
    hi = lo + step
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(lo) * f(mid) > 0 else (lo, mid)
    speed = math.sqrt(geometry.shear_modulus_pa / geometry.steel_density_kg_m3)
    return 0.5 * (lo + hi) * speed / (2 * math.pi * geometry.pipe_length_m)


@pytest.mark.parametrize("name", ["base", "deep"])
@pytest.mark.parametrize("top", [None, 2900.0])
def test_first_mode_of_the_distributed_string_is_the_shafts_with_end_inertias(name, top):
    """The distributed string's f₁ (the tuning SoftSpeed and Z-Torque take on that model)
    against the closed form of a shaft between the drive's and the BHA's inertias: the pipe's
    own inertia puts it well below the lumped √(C(1/I + 1/J))/(2π) (base: 0.57 vs 0.76 Hz)."""
    preset = load_preset(name)
    f1 = first_mode_frequency_hz(preset, top, string_model="distributed")
    exact = _shaft_with_end_inertias_hz(preset.string, math.inf if top is None else top,
                                        preset.rig.bha_inertia_kg_m2)
    assert f1 == pytest.approx(exact, rel=1e-3)
    assert f1 < 0.9 * first_mode_frequency_hz(preset, top)


@pytest.mark.parametrize("f_hz", [0.17, 0.76, 1.3])
def test_auto_tune_finds_a_known_frequency_in_a_noisy_torque(f_hz):
    """A stick-slip-like torque (fundamental and harmonics), trend and noise, 60 s at 100 Hz."""
    rng = np.random.default_rng(7)
    h = 0.01
    t = np.arange(6000) * h
    phase = 2 * math.pi * f_hz * t + rng.uniform(0, 2 * math.pi)
    torque = (8000 + 30 * t + 1500 * np.sin(phase) + 500 * np.sin(2 * phase + 1)
              + 200 * np.sin(3 * phase + 2) + rng.normal(0, 400, t.size))
    assert dominant_frequency_hz(torque, h) == pytest.approx(f_hz, rel=0.01)
    gains = auto_tune_soft_speed(torque, h, 302.0, 2900.0)
    assert gains.ki_nm_rad == pytest.approx((2 * math.pi * f_hz) ** 2 * 2900.0, rel=0.021)
    assert gains.kp_nm_s_rad == pytest.approx(4 * 302.0)


@pytest.mark.parametrize(("name", "gains", "bad"), [
    ("stiff_pi", {"kp_nm_s_rad": float("nan")}, "kp_nm_s_rad"),
    ("stiff_pi", {"ki_nm_rad": -1.0}, "ki_nm_rad"),
    ("stiff_pi", {"torque_max_nm": float("inf")}, "torque_max_nm"),
    ("stiff_pi", {"torque_min_nm": 10.0, "torque_max_nm": 5.0}, "torque_max_nm"),
    ("soft_speed", {"tuning_frequency_hz": 0.0}, "tuning_frequency_hz"),
    ("soft_speed", {"compensated_inertia_kg_m2": 2900.0}, "compensated_inertia_kg_m2"),
    ("soft_speed", {"kp_over_impedance": float("inf")}, "kp_over_impedance"),
    ("z_torque", {"alpha": -0.1}, "alpha"),
    ("z_torque", {"torque_lowpass_hz": 60.0}, "torque_lowpass_hz"),   # above 50 Hz Nyquist
    ("z_torque", {"highpass_hz": 3.0}, "highpass_hz"),                # above the 2.5 Hz LPF
    ("z_torque", {"speed_lowpass_hz": "fast"}, "speed_lowpass_hz"),
    ("stiff_pi", {"gain": 1.0}, "gain"),                              # unknown
    ("kinematic", {"alpha": 1.0}, "alpha"),
])
def test_bad_gains_are_refused_by_name(name, gains, bad):
    with pytest.raises(ParameterError, match=bad):
        make_law(name, 0.01, 302.0, 2900.0, **gains)


@pytest.mark.parametrize(("args", "bad"), [
    (("stiff_pi", 0.0, 302.0, 2900.0), "h_s"),
    (("stiff_pi", 0.01, float("nan"), 2900.0), "impedance_nm_s_rad"),
    (("z_torque", 0.01, 302.0, -1.0), "top_drive_inertia_kg_m2"),
    (("pid", 0.01, 302.0, 2900.0), "pid"),
])
def test_bad_law_arguments_are_refused_by_name(args, bad):
    with pytest.raises(ValueError, match=bad):
        make_law(*args)


def test_held_lag_is_the_exact_exponential_of_a_held_step():
    """A step held from the first sample: after k more samples the lag shows
    1 - exp(-k h/tau) exactly (the discretisation of a held input is exact; a linearised
    decay 1 - h/tau is 0.5 % off here after 10 samples)."""
    from drill_sim.control.filters import HeldLag
    h, tau = 1e-3, 0.01
    lag = HeldLag(tau, h)
    lag.settle(0.0)
    shown = [lag.step(1.0) for _ in range(30)]
    expected = [1.0 - math.exp(-k * h / tau) for k in range(30)]
    assert shown == pytest.approx(expected, rel=1e-12, abs=1e-15)


def test_a_steep_trend_is_removed_before_the_peak_is_sought():
    """A torque climbing 5 kN·m/s (the string winding up as the bit sticks) under a 1 kN·m,
    0.5 Hz oscillation: the trend's low-frequency energy would outweigh the peak were it
    kept (or doubled)."""
    h = 0.01
    t = np.arange(6000) * h
    torque = 8000 + 5000 * t + 1000 * np.sin(2 * math.pi * 0.5 * t + 0.3)
    assert dominant_frequency_hz(torque, h) == pytest.approx(0.5, rel=0.01)


def _padded_bin_hz(n: int, h: float) -> float:
    """The spectrum's spacing [Hz] after padding n samples to the next power of two ≥ 4 n."""
    return 1.0 / (2 ** math.ceil(math.log2(4 * n)) * h)


@pytest.mark.parametrize("fraction", [0.0, 0.25, 0.5])
def test_a_clean_tone_between_bins_is_found_to_a_thousandth_of_a_bin(fraction):
    """Hann window, log-parabola refinement: a pure tone anywhere between two padded bins
    (measured here: within 8e-4 of a bin) comes back to 2e-3 of a bin, at any amplitude
    (the spectrum's scale drops out of the log-parabola)."""
    h, n = 0.01, 1000
    df = _padded_bin_hz(n, h)
    f0 = 250 * df + fraction * df
    tone = np.sin(2 * math.pi * f0 * np.arange(n) * h + 0.4)
    for amplitude in (1.0, 1e-9):
        assert abs(dominant_frequency_hz(amplitude * tone, h) - f0) < 2e-3 * df


def test_the_band_is_the_one_asked_for():
    """A strong tone below f_min and one above f_max are not the answer; the weaker tone
    inside the band is."""
    h, n = 0.01, 2000
    t = np.arange(n) * h
    x = 5 * np.sin(2 * math.pi * 1.0 * t) + np.sin(2 * math.pi * 4.0 * t) + 5 * np.sin(
        2 * math.pi * 20.0 * t)
    assert dominant_frequency_hz(x, h, f_min_hz=2.0, f_max_hz=10.0) == pytest.approx(4.0,
                                                                                    abs=1e-3)
    assert dominant_frequency_hz(x, h, f_max_hz=10.0) == pytest.approx(1.0, abs=1e-3)
    assert dominant_frequency_hz(x, h, f_min_hz=2.0) == pytest.approx(20.0, abs=1e-3)


def test_a_series_without_oscillation_is_refused():
    for flat in (np.full(100, 3.0), 5.0 + 2.0 * np.arange(100.0)):
        with pytest.raises(ValueError, match="no oscillation"):
            dominant_frequency_hz(flat, 0.01)


def test_the_band_takes_its_edges():
    """A tone on the band's top bin is found there; a band of a single bin gives that bin."""
    h, n = 0.01, 1000
    df = _padded_bin_hz(n, h)
    f0 = 300 * df
    tone = np.sin(2 * math.pi * f0 * np.arange(n) * h + 0.2)
    assert abs(dominant_frequency_hz(tone, h, f_max_hz=f0) - f0) < 2e-3 * df
    assert abs(dominant_frequency_hz(tone, h, f_min_hz=f0, f_max_hz=f0) - f0) < 2e-3 * df


def test_soft_speed_tuning_defaults_and_the_auto_tunes_band():
    """tune_soft_speed with nothing given: k_p 4, f_t 0.2 Hz, J_c 0 (msg_docs/control.md).
    The auto-tune looks from f_min to 5 Hz by default: a stronger line at 5.5 Hz is outside,
    one at 1 Hz below f_min = 2 Hz too; the gains given pass through."""
    from drill_sim.control import tune_soft_speed
    gains = tune_soft_speed(302.0, 2900.0)
    assert gains == pytest.approx((4 * 302.0, (2 * math.pi * 0.2) ** 2 * 2900.0, 0.2, 0.0),
                                  rel=1e-12)
    h = 0.01
    t = np.arange(6000) * h
    torque = (9000 + 800 * np.sin(2 * math.pi * 1.0 * t) + 500 * np.sin(2 * math.pi * 3.0 * t)
              + 1500 * np.sin(2 * math.pi * 5.5 * t))
    assert auto_tune_soft_speed(torque, h, 302.0, 2900.0).tuning_frequency_hz == (
        pytest.approx(1.0, abs=1e-3))
    tuned = auto_tune_soft_speed(torque, h, 302.0, 2900.0, f_min_hz=2.0, kp_over_impedance=2.0)
    assert tuned.tuning_frequency_hz == pytest.approx(3.0, abs=1e-3)
    assert tuned.kp_nm_s_rad == pytest.approx(2 * 302.0, rel=1e-12)
