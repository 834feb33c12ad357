"""The reference tunings (``control.reference``) against their rules in msg_docs/control.md,
computed here from the rig's parameters: f₁ of the string model the law runs on, Z-Torque's
K_p = max(50 Z, 6 J_TD ω₁), and the signals' periods, lags and noise read off the profile."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

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


def test_a_presets_commissioning_sets_its_gains_for_a_drives_signals_only():
    """long's ``commissioning`` section (control.md, "Commissioned on long") replaces the
    rule's speed low-pass and high-pass where Z-Torque reads a drive's sampled or noisy
    signals on the distributed string, and nowhere else: exact signals, the lumped string,
    other laws and presets without the section (deep too, long's string) keep the rule's
    gains."""
    long, field_a = load_preset("long"), load_preset("field_a")
    assert long.commissioned("z_torque") == {"speed_lowpass_hz": 4.5, "highpass_hz": 0.08}
    assert long.commissioned("soft_speed") == {} == field_a.commissioned("z_torque")
    assert field_a.commissioning == () == load_preset("base").commissioning
    assert hash(long) != hash(field_a)
    drive = reference_gains("z_torque", long, J, string_model="distributed",
                            sensor_profile="surface_rig")
    assert (drive["speed_lowpass_hz"], drive["highpass_hz"]) == (4.5, 0.08)
    for gains in (reference_gains("z_torque", long, J, string_model="distributed"),
                  reference_gains("z_torque", long, J, sensor_profile="surface_rig"),
                  reference_gains("z_torque", field_a, J, string_model="distributed",
                                  sensor_profile="surface_rig"),
                  reference_gains("z_torque", load_preset("deep"), J,    # long's string
                                  string_model="distributed", sensor_profile="surface_rig")):
        assert "speed_lowpass_hz" not in gains and "highpass_hz" not in gains
    assert reference_gains("soft_speed", long, J, string_model="distributed",
                           sensor_profile="surface_rig") == reference_gains(
        "soft_speed", long, J, string_model="distributed")


@pytest.mark.parametrize(("section", "words"), [
    ("[]", ["commissioning is list", "mapping of law names"]),
    ("{z_torque: {}}", ["commissioning.z_torque is empty"]),
    ("{z_torque: 4.5}", ["commissioning.z_torque is float", "gain names"]),
    ("{z_torque: {speed_lowpass_hz: .nan}}", ["commissioning.z_torque.speed_lowpass_hz",
                                              "nan"]),
    ("{z_torque: {speed_lowpass_hz: fast}}", ["speed_lowpass_hz = 'fast' is not a number"]),
    ("{z_torque: {speed_lowpass_hz: true}}", ["speed_lowpass_hz = True is not a number"]),
    ("{z_turk: {speed_lowpass_hz: 4.5}}", ["commissioning.z_turk",
                                          "expected z_torque, got 'z_turk'"]),
    ("{z_torque: {speed_lowpas_hz: 4.5}}", ["unknown gain(s) ['speed_lowpas_hz']",
                                            "speed_lowpass_hz"]),
    ("{z_torque: {speed_lowpass_hz: -1.0}}", ["'tuned': commissioning.z_torque: "
                                              "speed_lowpass_hz = -1.0 is out of range"]),
    ("{z_torque: {speed_lowpass_hz: 5000}}", ["'tuned': commissioning.z_torque: "
                                              "speed_lowpass_hz = 5000"]),
    ("{soft_speed: {derivative_corner_hz: 3.0}}", ["commissioning.soft_speed: only "
                                                   "z_torque's gains", "'soft_speed'"]),
    ("{z_torque: }", ["commissioning.z_torque is empty"]),
])
def test_a_bad_commissioning_section_is_refused_by_name(tmp_path, section, words):
    """A commissioning section that is not {z_torque: {gain: number}} with known gains in
    their ranges is refused, naming the preset and the entry, when the preset is loaded or
    (the law, gain names and ranges) when reference gains are computed, for any law, string
    model and signals: not only where the section would apply."""
    from drill_sim.core.parameters import ParameterError
    text = (Path(__file__).parents[2] / "drill_sim" / "presets" / "long.yaml").read_text()
    text = text[:text.index("commissioning:")] + f"commissioning: {section}\n"
    path = tmp_path / "tuned.yaml"
    path.write_text(text)
    for law, string_model, profile in (("z_torque", "distributed", "surface_rig"),
                                       ("z_torque", "lumped", None),
                                       ("soft_speed", "distributed", "ideal")):
        with pytest.raises(ParameterError) as info:
            reference_gains(law, load_preset(path), J, string_model=string_model,
                            sensor_profile=profile)
        for word in words:
            assert word in str(info.value)
