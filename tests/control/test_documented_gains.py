"""Every gain of every law as msg_docs/control.md documents it: its default, the values at the
ends of its range taken, the values beyond them refused with a message that names the gain.
The table below is the documentation's, written out by hand (not read from the code)."""

from __future__ import annotations

import math

import pytest

from drill_sim.control import ParameterError, make_law
from drill_sim.control.supervisor import law_gain_defaults

H, Z, J = 1e-3, 302.4, 2900.0          # Nyquist 500 Hz
NYQUIST = 0.5 / H

# law -> gain -> (documented default, values taken, values refused)
DOCUMENTED = {
    "stiff_pi": {
        "kp_nm_s_rad": (50 * Z, (0.0, 1e6), (-1.0,)),
        "ki_nm_rad": (5 * J, (0.0, 1e6), (-1.0,)),
    },
    "soft_speed": {
        "kp_over_impedance": (4.0, (1e-6, 1000.0), (0.0, 1000.5)),
        "tuning_frequency_hz": (0.2, (1e-6, 100.0), (0.0, 100.5)),
        "compensated_inertia_kg_m2": (0.0, (0.0, J - 1.0), (-1.0, J)),
        "derivative_corner_hz": (5.0, (1e-6, NYQUIST - 1.0), (0.0, NYQUIST)),
    },
    "z_torque": {
        "alpha": (0.25, (0.0, 10.0), (-0.1, 10.5)),
        "kp_nm_s_rad": (50 * Z, (0.0, 1e6), (-1.0,)),
        "ki_nm_rad": (5 * J, (0.0, 1e6), (-1.0,)),
        "speed_lowpass_hz": (10.0, (1e-6, NYQUIST - 1.0), (0.0, NYQUIST)),
        "torque_lowpass_hz": (2.5, (0.1, NYQUIST - 1.0), (0.0, NYQUIST)),
        "highpass_hz": (0.05, (1e-6, 2.4), (0.0, 2.5)),        # below torque_lowpass_hz
        "measurement_period_s": (0.0, (0.0, 1.0), (-0.1, 1.5)),
        "torque_signal_tau_s": (0.0, (0.0, 10.0), (-0.1, 10.5)),
        "speed_signal_tau_s": (0.0, (0.0, 10.0), (-0.1, 10.5)),
        "backoff_per_s": (0.0, (0.0, 1.0 / H), (-0.1, 1.0 / H + 1.0)),
        "saturation_target": (0.03, (1e-6, 0.5), (0.0, 0.51)),
        "alpha_min": (0.0, (0.0, 10.0), (-0.1, 10.5)),
    },
}
CASES = [(law, gain, *spec) for law, gains in DOCUMENTED.items() for gain, spec in gains.items()]


@pytest.mark.parametrize(("law", "gain", "default", "taken", "refused"), CASES)
def test_a_gain_has_its_documented_default_and_range(law, gain, default, taken, refused):
    assert law_gain_defaults(law, Z, J)[gain] == pytest.approx(default, rel=1e-12)
    for value in taken:
        make_law(law, H, Z, J, **{gain: value})
    for value in (*refused, math.nan, math.inf):
        with pytest.raises(ParameterError, match=rf"^{gain}\b"):
            make_law(law, H, Z, J, **{gain: value})


@pytest.mark.parametrize("law", list(DOCUMENTED))
def test_the_sample_period_is_refused_by_name(law):
    for bad in (0.0, -1e-3, 1.5, math.nan):
        with pytest.raises(ParameterError, match=r"^h_s\b"):
            make_law(law, bad, Z, J)
    make_law(law, 1.0, Z, J, **({"speed_lowpass_hz": 0.4, "torque_lowpass_hz": 0.3,
                                 "highpass_hz": 0.01} if law == "z_torque" else
                                {"derivative_corner_hz": 0.4} if law == "soft_speed" else {}))


@pytest.mark.parametrize("law", ["stiff_pi", "soft_speed", "z_torque"])
def test_torque_limits_must_be_ordered_and_named(law):
    pi = make_law(law, H, Z, J).pi
    assert (pi.torque_min_nm, pi.torque_max_nm) == (-1e5, 1e5)      # documented: ∓1e5 N·m
    make_law(law, H, Z, J, torque_min_nm=-5.0, torque_max_nm=-4.0)
    for low, high in ((1.0, 0.0), (-5.0, -5.0)):                   # max above min
        with pytest.raises(ParameterError, match="torque_min_nm"):
            make_law(law, H, Z, J, torque_min_nm=low, torque_max_nm=high)
    for gain in ("torque_min_nm", "torque_max_nm"):
        with pytest.raises(ParameterError, match=rf"^{gain}\b"):
            make_law(law, H, Z, J, **{gain: math.nan})
