"""The distributed string's damped modes off bottom (``string_modes``, the ``modes`` of
``drill_sim stability --string-model distributed``): the exact roots of the continuously
damped pipe (viscous and Kelvin-Voigt, the top drive's boundary), computed independently in SI
from the preset's geometry (``pipe_theory``); every mode up to the fifth damped >= 2 % in the
shipped presets, in the theory and in the simulation; the simulation ringing at its modes and
leaving none undamped."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from pipe_theory import damped_roots, pipe
from test_distributed_damping import _band_mode

from drill_sim.core import distributed_kernel as dk
from drill_sim.core import load_preset
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.distributed_simulator import StringSimulator
from drill_sim.core.stability_distributed import string_modes
from drill_sim.core.top_drive import DriveGroups

H = 5e-4
PRESETS = ("base", "deep", "shallow", "long", "field_a")


def _drive(p, mode: str, lag_s: float = 0.0):
    td = replace(p.top_drive, top_drive_mode=mode, drive_lag_s=lag_s)
    return td, td.groups(p.rig.scales, p.rig.bha_inertia_kg_m2)


def _modes(p, drive: DriveGroups, geometry=None, continuous: bool = True):
    g = p.string if geometry is None else geometry
    return string_modes(geometry_waves(p.rig, g, H, continuous=continuous), p.rig.groups.psi,
                        drive)


@pytest.mark.parametrize("name", PRESETS)
@pytest.mark.parametrize("mode, lag_s", [("kinematic", 0.0), ("torque", 0.0), ("speed", 0.02)])
def test_modes_are_the_exact_roots_of_the_damped_pipe(name, mode, lag_s):
    """Five torsional and five axial roots, each the root of the pipe's own frequency equation
    in SI (k^2 = s (m s + c)/(K (1 + eta s)); the top: held, the drive's inertia under a held
    torque, or its PI through the lag) to 1e-8: a wrong damping law, scale, boundary or a
    missed mode shows."""
    p = load_preset(name)
    td, drive = _drive(p, mode, lag_s)
    ts, c_unit = p.rig.scales.time_s, p.rig.scales.stiffness_nm_per_rad
    j = td.top_drive_inertia_kg_m2
    kp, ki = drive.kp * c_unit * ts, drive.ki * c_unit        # back to SI from the groups

    def top(s):
        if mode == "torque":
            return j * s * s
        return j * s * s + (kp * s + ki) / (1.0 + lag_s * s)

    res = _modes(p, drive)
    assert res.complete
    expected = {"torsional": damped_roots("torsion", pipe("torsion", p), 5,
                                          None if mode == "kinematic" else top),
                "axial": damped_roots("axial", pipe("axial", p), 5)}
    for kind, found in (("torsional", res.torsional), ("axial", res.axial)):
        assert [m.kind for m in found] == [kind] * 5
        for m, root in zip(found, expected[kind], strict=True):
            assert m.root / ts == pytest.approx(root, rel=1e-8), (kind, m, root)


@pytest.mark.parametrize("name", PRESETS)
def test_shipped_presets_damp_every_mode_up_to_the_fifth(name):
    """>= 2 % for every torsional and axial mode up to the fifth of the exact pipe, with the
    top held, free under the drive's inertia, or under its PI."""
    p = load_preset(name)
    for mode in ("kinematic", "torque", "speed"):
        res = _modes(p, _drive(p, mode)[1])
        ratios = [m.damping_ratio for m in res.torsional + res.axial]
        assert res.complete and len(ratios) == 10
        assert min(ratios) >= 0.02, (mode, ratios)


@pytest.mark.slow("the lines' transfer matrices over 9 segments, evaluated on a Newton grid "
                  "for six boxes a preset: ~1 s each")
@pytest.mark.parametrize("name", PRESETS)
def test_simulated_string_damps_every_mode_up_to_the_fifth(name):
    """Likewise for the simulation's lines (stations, relative dashpots and low-passes: their
    transfer matrices), top held and free under the drive's inertia (the least damped first
    torsional mode)."""
    p = load_preset(name)
    for mode in ("kinematic", "torque"):
        res = _modes(p, _drive(p, mode)[1], continuous=False)
        ratios = [m.damping_ratio for m in res.torsional + res.axial]
        assert res.complete and len(ratios) == 10
        assert min(ratios) >= 0.02, (mode, ratios)


@pytest.mark.slow("a ring-down per mode, four times the mode's decay time: ~1 s a preset")
@pytest.mark.parametrize("name", ["base", "shallow"])
def test_simulation_rings_at_its_modes_close_to_the_exact_pipe(name):
    """Off bottom, top held, a kick of top speed and of hook force: the simulated string's first
    two torsional and axial modes decay at the roots of its own lines' transfer matrices (3 %)
    and ring at their frequencies (1 %), so the kernel steps what the lines describe; and
    those are the exact pipe's (frequency 0.5 %, damping ratio 6 %: the stations lump the
    damping; measured 0.1-5.4 %, and -3 to -17 % for modes 3 to 5, msg_docs/model.md)."""
    p = load_preset(name)
    lines = _modes(p, DriveGroups(), continuous=False)
    exact = _modes(p, DriveGroups())
    for col, kind in ((dk.O_T_BOTTOM, "torsional"), (dk.O_F_BOTTOM, "axial")):
        for mode, ref in zip(getattr(lines, kind)[:2], getattr(exact, kind)[:2], strict=True):
            assert mode.frequency == pytest.approx(ref.frequency, rel=5e-3), (kind, mode, ref)
            assert mode.damping_ratio == pytest.approx(ref.damping_ratio, rel=6e-2), \
                (kind, mode, ref)
            sim = StringSimulator(p.rig.groups, geometry_waves(p.rig, p.string, H))
            sim.start_at_rest(gap=1e9)
            sim.set_commands(0.0, 0.1)
            sim.advance(round(0.05 / H))
            sim.set_commands(1.0, 0.0)
            sim.advance(round(0.05 / H))
            sim.set_commands(0.0, 0.0)
            dt = 0.2 / mode.frequency
            rows = sim.record(4.0 / -mode.root.real, dt)
            measured = _band_mode(rows[:, col], dt, mode.frequency)
            assert measured.real == pytest.approx(mode.root.real, rel=3e-2), (kind, measured)
            assert measured.imag == pytest.approx(mode.root.imag, rel=1e-2), (kind, measured)


def test_no_mode_of_the_simulated_string_is_left_undamped():
    """A kick rings every mode, also those whose nodes sit at every damping station (no
    dashpot at a station, fixed or relative, reaches them: at 1/D_part, 50 Hz on shallow);
    the material's low-pass on every passage damps them as the pipe's material does, so 100
    t* later what rings above the fifth mode is < 1e-3 of what rang right after the kick
    (without the low-passes ~1)."""
    p = load_preset("shallow")
    sim = StringSimulator(p.rig.groups, geometry_waves(p.rig, p.string, H))
    f5 = _modes(p, DriveGroups()).torsional[-1].frequency      # [1/t*]
    sim.start_at_rest(gap=1e9)
    sim.set_commands(0.0, 0.1)
    sim.advance(round(0.05 / H))
    sim.set_commands(0.0, 0.0)

    def high_rms(duration: float) -> float:
        x = sim.record(duration, H)[:, dk.O_T_BOTTOM]
        spec = np.fft.rfft((x - x.mean()) * np.hanning(x.size))
        om = 2.0 * math.pi * np.fft.rfftfreq(x.size, H)
        return float(np.sqrt(np.sum(np.abs(spec[om > 1.5 * f5]) ** 2)))

    early = high_rms(10.0)
    sim.advance(round(100.0 / H))
    assert high_rms(10.0) < 1e-3 * early
