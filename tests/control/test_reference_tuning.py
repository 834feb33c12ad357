"""The reference tunings (``control.reference``) against their rules in msg_docs/control.md,
computed here from the rig's parameters: f₁ of the string model the law runs on, Z-Torque's
K_p = max(50 Z, 6 J_TD ω₁), and the signals' periods, lags and noise read off the profile."""

from __future__ import annotations

import dataclasses
import math

import pytest

from drill_sim.control.reference import reference_gains, signal_alignment
from drill_sim.control.tuning import first_mode_frequency_hz, pipe_impedance
from drill_sim.core.presets import load_preset
from drill_sim.core.sensor_profile import ChannelSpec, load_profile

J = 2900.0


@pytest.fixture(scope="module")
def base():
    return load_preset("base")


def _lumped_f1_hz(preset, j: float) -> float:
    c, i = preset.rig.torsional_stiffness_nm_per_rad, preset.rig.bha_inertia_kg_m2
    return math.sqrt(c * (1.0 / i + 1.0 / j)) / (2.0 * math.pi)


def test_soft_speed_is_tuned_at_the_first_mode_of_its_string_model(base):
    f1 = _lumped_f1_hz(base, J)
    assert reference_gains("soft_speed", base, J) == pytest.approx(
        {"tuning_frequency_hz": f1, "compensated_inertia_kg_m2": 0.95 * J,
         "derivative_corner_hz": 25.0 * f1}, rel=1e-12)
    waves = reference_gains("soft_speed", base, J, string_model="distributed")
    f1_waves = first_mode_frequency_hz(base, J, string_model="distributed")
    assert waves["tuning_frequency_hz"] == pytest.approx(f1_waves, rel=1e-12)
    assert f1_waves < 0.9 * f1                     # the pipe's own inertia: a different tuning


def test_z_torques_gain_is_the_larger_of_50_z_and_six_j_omega(base):
    z = pipe_impedance(base)
    stiff = reference_gains("z_torque", base, J)
    assert stiff == pytest.approx({"kp_nm_s_rad": 6.0 * J * 2 * math.pi * _lumped_f1_hz(base, J),
                                   "alpha": 0.5}, rel=1e-12)
    light = 20.0                                    # a light drive: 50 Z is the larger
    assert reference_gains("z_torque", base, light)["kp_nm_s_rad"] == pytest.approx(50.0 * z,
                                                                                     rel=1e-12)
    assert reference_gains("stiff_pi", base, J) == {} == reference_gains("kinematic", base, J)


def test_z_torque_is_told_what_its_signals_are(base):
    """surface_rig: speed and motor torque at 100 Hz, the torque through a 5 ms lag, the speed
    noisy: period 0.01 s, torque_signal_tau_s 0.005, the torque low-pass down to 2 f₁."""
    f1 = _lumped_f1_hz(base, J)
    gains = reference_gains("z_torque", base, J, sensor_profile="surface_rig")
    assert {k: v for k, v in gains.items() if k not in ("kp_nm_s_rad", "alpha")} == (
        pytest.approx({"measurement_period_s": 0.01, "torque_signal_tau_s": 0.005,
                       "torque_lowpass_hz": 2.0 * f1}, rel=1e-12))
    assert signal_alignment("ideal", f1) == {} == signal_alignment(None, f1)


def test_the_alignment_reads_each_property_of_the_signals():
    """A profile given as an object; each property present only where the profile has it:
    the slower of the two rates, each signal's own lag, the low-pass only for a noisy speed."""
    ideal = load_profile("ideal")
    channels = dict(ideal.channels)
    channels["top_drive_speed_rad_s"] = ChannelSpec(rate_hz=0.5, filter_tau_s=0.02)
    channels["motor_torque_nm"] = ChannelSpec(rate_hz=2.0, filter_tau_s=0.5, noise_std=3.0)
    profile = dataclasses.replace(ideal, channels=channels)
    assert signal_alignment(profile, 0.7) == {"measurement_period_s": 2.0,
                                              "torque_signal_tau_s": 0.5,
                                              "speed_signal_tau_s": 0.02}
    channels["top_drive_speed_rad_s"] = ChannelSpec(noise_std=0.5)
    channels["motor_torque_nm"] = ChannelSpec()
    assert signal_alignment(profile, 0.7) == {"torque_lowpass_hz": 1.4}


def test_on_the_distributed_string_z_torque_is_capped_for_a_drives_signals():
    """control.md, "Tuning for the node's rates": on the distributed string Z-Torque's α is 0.3
    and its torque low-pass is the exact signals' passive one, capped for sampled or noisy
    signals at (α K_p/Z) ω_T = 1100 rad/s; computed here from K_p and Z. The noise rule's
    2 f₁ is not used there."""
    for name in ("base", "long"):
        preset = load_preset(name)
        z, exact = pipe_impedance(preset), reference_gains(
            "z_torque", preset, J, string_model="distributed")
        assert exact["alpha"] == 0.3
        cap_hz = 1100.0 * z / (0.3 * exact["kp_nm_s_rad"]) / (2.0 * math.pi)
        ideal = load_profile("ideal")
        noisy = dataclasses.replace(ideal, channels={
            **ideal.channels, "top_drive_speed_rad_s": ChannelSpec(noise_std=0.005)})
        for profile in ("surface_rig", noisy):
            gains = reference_gains("z_torque", preset, J, string_model="distributed",
                                    sensor_profile=profile)
            assert gains["torque_lowpass_hz"] == pytest.approx(
                min(exact["torque_lowpass_hz"], cap_hz), rel=1e-12)
    # base: the cap binds (29 Hz exact, 2.9 Hz capped); long: 7.6 Hz exact, 6.8 Hz capped
    base = load_preset("base")
    assert reference_gains("z_torque", base, J, string_model="distributed",
                           sensor_profile="surface_rig")["torque_lowpass_hz"] == pytest.approx(
        2.85, abs=0.01)
