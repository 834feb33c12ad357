"""Every refusal of the control package, word for word, as the user reads it.

The other tests match a refusal's key words (the parameter's name, its range); this table holds
the whole line, so that a message which loses its value, its range or its unit, or says the
wrong one, fails here. A deliberate change of wording is made in this table too."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from drill_sim.control import ParameterError, SurfaceMeasurement, make_law, scenarios, tuning
from drill_sim.control.closed_loop import run_loop, tick_commands
from drill_sim.control.evaluation import LoopSettings
from drill_sim.control.filters import FilteredDerivative, FirstOrderSection, HeldLag
from drill_sim.control.sampled_loop import SampledLoop, controller_status
from drill_sim.control.supervisor import Supervisor
from drill_sim.core.presets import load_preset
from drill_sim.session.scenario import Scenario

H, Z, J = 1e-3, 302.4, 2900.0
M = SurfaceMeasurement(0.0, 6.0, 5000.0, 5000.0)
BASE = load_preset("base")
NO_STRING = dataclasses.replace(BASE, string=None)
SINE = np.sin(np.arange(64))
SHORT = Scenario.steady(60.0, 100.0, duration_s=1.0, window_start_s=0.5)

REFUSALS = {
    "law = 'pid' is unknown: expected one of kinematic, stiff_pi, soft_speed, z_torque, off":
        lambda: make_law("pid", H, Z, J),
    "law 'stiff_pi': unknown gain(s) ['alpha']; expected kp_nm_s_rad, ki_nm_rad, "
    "torque_min_nm, torque_max_nm":
        lambda: make_law("stiff_pi", H, Z, J, alpha=1.0),
    "law 'off': unknown gain(s) ['alpha']; expected none":
        lambda: make_law("off", H, Z, J, alpha=1.0),
    "h_s = 2.0 is out of range: expected a finite number > 0 and <= 1":
        lambda: make_law("stiff_pi", 2.0, Z, J),
    "impedance_nm_s_rad = -1.0 is out of range: expected a finite number > 0":
        lambda: make_law("stiff_pi", H, -1.0, J),
    "top_drive_inertia_kg_m2 = 0.0 is out of range: expected a finite number > 0":
        lambda: make_law("stiff_pi", H, Z, 0.0),
    "kp_nm_s_rad = -1.0 is out of range: expected a finite number >= 0":
        lambda: make_law("stiff_pi", H, Z, J, kp_nm_s_rad=-1.0),
    "ki_nm_rad = -1.0 is out of range: expected a finite number >= 0":
        lambda: make_law("z_torque", H, Z, J, ki_nm_rad=-1.0),
    "torque_max_nm = 0.0 is out of range: expected a finite number > torque_min_nm = 1.0":
        lambda: make_law("stiff_pi", H, Z, J, torque_min_nm=1.0, torque_max_nm=0.0),
    "speed_lowpass_hz = 600.0 is out of range: expected a finite number > 0 and < the Nyquist "
    "frequency 500 Hz (h_s = 0.001 s)":
        lambda: make_law("z_torque", H, Z, J, speed_lowpass_hz=600.0),
    "torque_lowpass_hz = 0.0 is out of range: expected a finite number > 0":
        lambda: make_law("z_torque", H, Z, J, torque_lowpass_hz=0.0),
    "highpass_hz = 3.0 is out of range: expected < torque_lowpass_hz = 2.5":
        lambda: make_law("z_torque", H, Z, J, highpass_hz=3.0),
    "alpha = 11.0 is out of range: expected a finite number >= 0 and <= 10":
        lambda: make_law("z_torque", H, Z, J, alpha=11.0),
    "measurement_period_s = 2.0 is out of range: expected a finite number >= 0 and <= 1":
        lambda: make_law("z_torque", H, Z, J, measurement_period_s=2.0),
    "torque_signal_tau_s = -1.0 is out of range: expected a finite number >= 0 and <= 10":
        lambda: make_law("z_torque", H, Z, J, torque_signal_tau_s=-1.0),
    "speed_signal_tau_s = 11.0 is out of range: expected a finite number >= 0 and <= 10":
        lambda: make_law("z_torque", H, Z, J, speed_signal_tau_s=11.0),
    "tuning_frequency_hz = 1.0 is out of range: expected < the Nyquist frequency 1 Hz":
        lambda: make_law("soft_speed", 0.5, Z, J, tuning_frequency_hz=1.0,
                         derivative_corner_hz=0.5),
    "kp_over_impedance = 0.0 is out of range: expected a finite number > 0 and <= 1000":
        lambda: make_law("soft_speed", H, Z, J, kp_over_impedance=0.0),
    "compensated_inertia_kg_m2 = 2900.0 is out of range: expected >= 0 and < "
    "top_drive_inertia_kg_m2 = 2900.0":
        lambda: make_law("soft_speed", H, Z, J, compensated_inertia_kg_m2=J),
    "derivative_corner_hz = 500.0 is out of range: expected a finite number > 0 and < the "
    "Nyquist frequency 500 Hz (h_s = 0.001 s)":
        lambda: make_law("soft_speed", H, Z, J, derivative_corner_hz=500.0),
    "speed_set_rad_s = nan is out of range: expected a finite number":
        lambda: make_law("stiff_pi", H, Z, J).set_speed(math.nan),
    "current_output = inf is out of range: expected a finite number":
        lambda: make_law("stiff_pi", H, Z, J).bumpless_start(math.inf, M),
    "current_output = nan is out of range: expected a finite number":
        lambda: make_law("off", H, Z, J).bumpless_start(math.nan, M),
    "current_output = -inf is out of range: expected a finite number":
        lambda: make_law("soft_speed", H, Z, J).bumpless_start(-math.inf, M),
    "current_output = 'x' is not a number: expected a finite number":
        lambda: make_law("z_torque", H, Z, J).bumpless_start("x", M),
    "speed_set_rad_s = 'fast' is not a number: expected a finite number":
        lambda: Supervisor(H, Z, J, "z_torque").set_speed("fast"),
    "h_s = -1.0 is out of range: expected a finite number > 0":
        lambda: FirstOrderSection(1.0, -1.0),
    "corner_hz = -2.0 is out of range: expected a finite number > 0":
        lambda: FilteredDerivative(-2.0, H),
    "tau_s = -1.0 is out of range: expected a finite number >= 0 and <= 10":
        lambda: HeldLag(-1.0, H),
    "series: no oscillation once its linear trend is removed: expected a torque that varies "
    "about its trend":
        lambda: tuning.dominant_frequency_hz(np.arange(32.0), 0.01),
    "top_drive_speed_rad_s = inf is out of range: expected a finite number":
        lambda: make_law("z_torque", H, Z, J).bumpless_start(
            1.0, M._replace(top_drive_speed_rad_s=math.inf)),
    "motor_torque_nm = nan is out of range: expected a finite number":
        lambda: make_law("z_torque", H, Z, J).bumpless_start(
            1.0, M._replace(motor_torque_nm=math.nan)),
    "law = 'kinematic' is a speed pass-through, not a controller of the motor torque: expected "
    "one of stiff_pi, soft_speed, z_torque, off":
        lambda: Supervisor(H, Z, J, "kinematic"),
    "speed_set_rad_s = -inf is out of range: expected a finite number":
        lambda: Supervisor(H, Z, J, "z_torque", speed_set_rad_s=-math.inf),
    "scenario set 'nope' is unknown: expected one of standard, grid, wob_step, speed_ramp, "
    "switch_on, a rig scenario (controller_on, startup_off_bottom, step_test, tag_bottom) or a "
    "scenario YAML":
        lambda: scenarios.named(["nope"]),
    "preset 'base' has no 'string' section: the pipe's impedance needs its geometry (OD, ID, "
    "G, rho)":
        lambda: tuning.pipe_impedance(NO_STRING),
    "expected a Preset, StringGeometry or preset name, got int":
        lambda: tuning.pipe_impedance(3),
    "expected a Preset, RigParameters or preset name, got float":
        lambda: tuning.first_mode_frequency_hz(3.0),
    "string_model = 'waves': expected lumped or distributed":
        lambda: tuning.first_mode_frequency_hz("base", string_model="waves"),
    "series: expected at least 16 finite samples, got 15 of 15":
        lambda: tuning.dominant_frequency_hz([1.0] * 15, 0.01),
    "series: expected at least 16 finite samples, got 15 of 16":
        lambda: tuning.dominant_frequency_hz([1.0] * 15 + [math.nan], 0.01),
    "series: expected at least 16 finite samples, got 0 of 16":
        lambda: tuning.dominant_frequency_hz(np.ones((4, 4)), 0.01),
    "band 10..10.1 Hz holds no frequency bin of a 0.16 s record":
        lambda: tuning.dominant_frequency_hz(SINE[:16], 0.01, f_min_hz=10.0, f_max_hz=10.1),
    "f_min_hz = -1.0 is out of range: expected a finite number >= 0":
        lambda: tuning.dominant_frequency_hz(SINE, 0.01, f_min_hz=-1.0),
    "f_max_hz = 0.0 is out of range: expected a finite number > 0":
        lambda: tuning.dominant_frequency_hz(SINE, 0.01, f_max_hz=0.0),
    "h_s = 0.0 is out of range: expected a finite number > 0":
        lambda: tuning.dominant_frequency_hz(SINE, 0.0),
    "tuning_frequency_hz = 101.0 is out of range: expected a finite number > 0 and <= 100":
        lambda: tuning.tune_soft_speed(Z, J, f_t_hz=101.0),
    "kp_over_impedance = 1001.0 is out of range: expected a finite number > 0 and <= 1000":
        lambda: tuning.tune_soft_speed(Z, J, kp_over_impedance=1001.0),
    "compensated_inertia_kg_m2 = -1.0 is out of range: expected a finite number >= 0":
        lambda: tuning.tune_soft_speed(Z, J, compensated_inertia_kg_m2=-1.0),
    "top_drive_inertia_kg_m2 = -1.0 is out of range: expected a finite number > 0":
        lambda: tuning.first_mode_frequency_hz("base", -1.0),
    "impedance_nm_s_rad = nan is out of range: expected a finite number > 0":
        lambda: tuning.tune_soft_speed(math.nan, J),
    "top_drive_inertia_kg_m2 = -2.0 is out of range: expected a finite number > 0":
        lambda: tuning.tune_soft_speed(Z, -2.0),
    "x_tau_s = 11.0 is out of range: expected a finite number >= 0 and <= 10":
        lambda: HeldLag(11.0, H, name="x_tau_s"),
    "corner_hz = 0.0 is out of range: expected a finite number > 0":
        lambda: FirstOrderSection(0.0, H),
    "sample_period_s = 2.0 is out of range: expected a finite number > 0 and <= 1":
        lambda: run_loop(BASE, SHORT,
                         LoopSettings(law="kinematic", sample_period_s=2.0)),
    "scenario '60rpm_100kN' start_rpm = -5.0 is out of range: expected a finite number > 0":
        lambda: run_loop(BASE, dataclasses.replace(SHORT, start_rpm=-5.0),
                         LoopSettings(law="kinematic")),
    "wob_kn up to 2000 kN is out of range: expected at most W_s = 338.359 kN":
        lambda: tick_commands(BASE, dataclasses.replace(
            SHORT, load=Scenario.steady(60.0, 2000.0).load), 0.01),
}


@pytest.mark.parametrize("message", list(REFUSALS))
def test_each_refusal_says_exactly_this(message):
    with pytest.raises(ParameterError) as caught:
        REFUSALS[message]()
    assert str(caught.value) == message


def test_the_controllers_status_words():
    core = Supervisor(H, Z, J, "z_torque")
    window = {"samples": 10, "saturation_fraction": 0.0, "windup_fraction": 0.0}
    assert controller_status(core, window, False, "rig_a") == (True, "waiting for rig_a's rate_hz")
    assert controller_status(core, window, True, "rig_a") == (False, "controlling")
    assert controller_status(core, {**window, "samples": 0}, True, "r") == (
        True, "no samples: the rig's inputs are not arriving")
    for key in ("saturation_fraction", "windup_fraction"):
        assert controller_status(core, {**window, key: 0.51}, True, "r") == (
            True, "output saturated")
        assert controller_status(core, {**window, key: 0.5}, True, "r") == (False, "controlling")
    core.set_enabled(False)
    assert controller_status(core, window, True, "r") == (False, "disabled")


def test_a_skipped_sample_names_its_time():
    loop = SampledLoop(3)
    command, why = loop.step(Supervisor(H, Z, J, "z_torque"), 1_234_567_890,
                             [6.0, math.nan, 5000.0])
    assert command is None
    assert why == "sample at 1.235 s skipped: non-finite input"
