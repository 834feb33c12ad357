"""Viscous damping per unit length of the pipe (the preset keys
``string.torsional_damping_nm_s_per_rad_m`` and ``string.axial_damping_n_s_per_m2``): the
simulated string's free modes decay at the roots of the continuously damped pipe's frequency
equation, and the keys are read in SI and checked."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from pipe_theory import first_root, lossless_string, pipe

from drill_sim.core import ParameterError, Rig, load_preset
from drill_sim.core import distributed_kernel as dk
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.distributed_simulator import StringSimulator
from drill_sim.core.presets import preset_from_dict
from drill_sim.core.resources import read_yaml

H = 5e-4


def _band_mode(x: np.ndarray, dt: float, near: float) -> complex:
    """decay + i frequency of the mode near ``near`` [rad/t*]: a Gaussian band-pass (15 %)
    in the frequency domain, then the slopes of log |y| and of the phase over the record's
    middle (a damped exponential passes a linear filter unchanged but for a factor)."""
    spec = np.fft.fft(x)
    om = np.fft.fftfreq(x.size, dt) * 2.0 * math.pi
    y = np.fft.ifft(spec * np.exp(-0.5 * ((om - near) / (0.15 * near)) ** 2))
    t = np.arange(x.size) * dt
    mid = (t > 0.2 * t[-1]) & (t < 0.6 * t[-1])
    return complex(np.polyfit(t[mid], np.log(np.abs(y[mid])), 1)[0],
                   np.polyfit(t[mid], np.unwrap(np.angle(y[mid])), 1)[0])


@pytest.mark.parametrize("name, torsional, axial", [("base", 0.05, 5.0), ("base", 0.02, 2.0),
                                                    ("deep", 0.02, 2.0)])
def test_free_modes_decay_as_the_continuously_damped_pipe(name, torsional, axial):
    """Off bottom, top held, a kick of top speed and hook force: the first torsional and axial
    modes decay at the continuously damped pipe's rate (1 %; measured 0.04-0.7 % with the 8
    dashpots at the centres of equal parts; at the parts' ends the torsional rate was 16 %
    off) and ring at its frequency (1e-3), both computed in SI from the geometry (so a wrong
    SI conversion of the damping or the density is caught, which a reference built from the
    code's own wave lines let through)."""
    p = load_preset(name)
    geometry = replace(lossless_string(p), torsional_damping_nm_s_per_rad_m=torsional,
                       axial_damping_n_s_per_m2=axial)
    waves = geometry_waves(p.rig, geometry, H)
    # the reference in SI from the geometry, in t* units (the one scale taken from the code)
    roots = [first_root(kind, pipe(kind, p, geometry)) * p.rig.scales.time_s
             for kind in ("torsion", "axial")]
    sim = StringSimulator(p.rig.groups, waves)
    sim.start_at_rest(gap=1e9)
    sim.set_commands(0.0, 0.1)
    sim.advance(round(0.3 / H))
    sim.set_commands(1.0, 0.0)
    sim.advance(round(0.3 / H))
    sim.set_commands(0.0, 0.0)
    rows = sim.record(3.0 / -roots[0].real + 3.0 / -roots[1].real, 0.02)
    for col, root in zip((dk.O_T_BOTTOM, dk.O_F_BOTTOM), roots, strict=True):
        measured = _band_mode(rows[:, col], 0.02, root.imag)
        assert measured.real == pytest.approx(root.real, rel=1e-2), (col, measured, root)
        assert measured.imag == pytest.approx(root.imag, rel=1e-3), (col, measured, root)


def test_steady_turn_costs_the_damping_torque():
    """Off bottom, the top turning steadily at Omega: the mean torque at the top is the
    damping c L Omega (SI, from the preset key through the scales; 1e-3: the start's step
    leaves a small ringing of the modes whose nodes sit on the dashpots, see model.md)."""
    p = load_preset("base")
    c = 0.05                                        # N m s/rad per m of pipe
    geometry = replace(lossless_string(p), torsional_damping_nm_s_per_rad_m=c)
    rig = Rig(p.rig, string_model="distributed", geometry=geometry)
    rig.start_at_rest(gap_m=10.0)
    rig.command(6.0, p.rig.submerged_weight_n)
    rig.advance(200.0)
    rig.reset_metrics_window()
    rig.advance(200.0)
    expected = c * geometry.pipe_length_m * 6.0
    assert rig.metrics()["mean_surface_torque_nm"] == pytest.approx(expected, rel=1e-3)


def test_preset_keys_are_read_in_si_default_to_a_lossless_pipe_and_are_checked():
    name, data = read_yaml("preset", "presets", "base")
    keys = ("torsional_damping_nm_s_per_rad_m", "axial_damping_n_s_per_m2",
            "torsional_retardation_time_s", "axial_retardation_time_s")
    bare = {k: v for k, v in data["string"].items() if k not in keys}
    assert all(getattr(preset_from_dict(name, {**data, "string": bare}).string, k) == 0.0
               for k in keys)
    string = dict(bare, torsional_damping_nm_s_per_rad_m=0.1, axial_damping_n_s_per_m2=3.0,
                  torsional_retardation_time_s=2e-3)
    preset = preset_from_dict(name, {**data, "string": string})
    waves = geometry_waves(preset.rig, preset.string, H)
    ts = preset.rig.scales.time_s
    scale = preset.rig.scales.stiffness_nm_per_rad * ts
    assert waves.torsion.dashpot.sum() == pytest.approx(0.1 * 1000.0 / scale, rel=1e-12)
    # the material's dashpot across a whole part: eta [t*] times the part's stiffness z/D,
    # 8/7 of it (the end halves carry none), less the low-pass's share at low frequency (0.1);
    # the low-pass: tau^2 = 0.2 eta D; the axial line has no material damping
    line = waves.torsion
    eta = 2e-3 / ts
    assert line.relative[1] == pytest.approx(0.9 * eta * line.z[1] / line.delay[1] * 8 / 7,
                                             rel=1e-12)
    assert line.relative[0] == line.relative[-1] == 0.0
    assert line.tau == pytest.approx(np.sqrt(0.2 * eta * line.delay), rel=1e-12)
    assert not waves.axial.relative.any() and not waves.axial.tau.any()
    for key in keys:
        for bad in (-1.0, math.nan, math.inf, "x"):
            with pytest.raises(ParameterError, match=key):
                preset_from_dict(name, {**data, "string": dict(string, **{key: bad})})
