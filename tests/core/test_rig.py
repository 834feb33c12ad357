"""The SI face of the core: commands, time keeping, run-time parameter changes, hoisting."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from drill_sim.core import Groups, ParameterError, Rig


def test_si_steady_start_reads_the_steady_state(base):
    rig = Rig(base.rig)
    rig.start_steady(base.top_drive_speed_rad_s, base.hook_load_n)
    rig.advance(0.5)
    s = rig.sample()
    st = rig.steady_state(base.top_drive_speed_rad_s, base.hook_load_n)
    assert s.wob_n == pytest.approx(1e5, rel=1e-6)
    assert s.bit_speed_rad_s == pytest.approx(2 * math.pi, rel=1e-6)
    assert s.tob_nm == pytest.approx(st.t0 * rig.scales.stiffness_nm_per_rad, rel=1e-6)
    assert s.time_s == pytest.approx(0.5, abs=rig.dt_s)


def test_a_perturbed_steady_start_speeds_only_the_bit(base):
    """perturbation p: the bit starts at (1 + p) times the steady speed, the top drive at
    the steady speed (the start every stick-slip run grows from)."""
    rig = Rig(base.rig)
    rig.start_steady(base.top_drive_speed_rad_s, base.hook_load_n, perturbation=0.01)
    s = rig.sample()
    assert s.bit_speed_rad_s == pytest.approx(1.01 * base.top_drive_speed_rad_s, rel=1e-12)
    assert s.top_drive_speed_rad_s == pytest.approx(base.top_drive_speed_rad_s, rel=1e-12)


def test_advance_to_counts_whole_steps(base):
    rig = Rig(base.rig, dt_s=1e-4)
    assert rig.advance_to(0.01) == 100
    assert rig.advance_to(0.01) == 0
    assert rig.advance_to(0.005) == 0            # never backwards
    with pytest.raises(ParameterError):
        rig.advance_to(math.nan)


def test_bad_commands_are_refused_and_change_nothing(base):
    rig = Rig(base.rig)
    rig.start_steady(base.top_drive_speed_rad_s, base.hook_load_n)
    before = rig.sim.commands
    for speed, hook in ((math.nan, 1e5), (-1.0, 1e5), (1.0, -5.0), (1.0, math.inf)):
        with pytest.raises(ParameterError):
            rig.command(speed, hook)
    assert rig.sim.commands == before


def test_parameter_change_keeps_the_physical_state(base):
    rig = Rig(base.rig)
    rig.start_steady(base.top_drive_speed_rad_s, base.hook_load_n, 1e-3)
    rig.advance(10.0)
    a = rig.sample()
    stiffer = replace(base.rig, torsional_stiffness_nm_per_rad=1200.0, bha_mass_kg=15000.0)
    rig.replace_parameters(stiffer)
    b = rig.sample()
    for field in ("time_s", "bit_speed_rad_s", "rop_m_s", "bit_depth_m", "bit_angle_rad",
                  "top_drive_angle_rad", "hole_depth_m"):
        assert getattr(b, field) == pytest.approx(getattr(a, field), rel=1e-6, abs=1e-9), field
    # the string torque follows the new stiffness at the same twist
    assert b.surface_torque_nm == pytest.approx(a.surface_torque_nm * 1200.0
                                                / base.rig.torsional_stiffness_nm_per_rad)
    rig.advance(5.0)
    assert math.isfinite(rig.sample().wob_n)
    with pytest.raises(ParameterError, match="blade_count"):
        rig.replace_parameters(replace(base.rig, blade_count=5))


def test_hook_load_above_string_weight_lifts_the_bit_at_the_hoisting_limit(base):
    rig = Rig(base.rig, hoist_speed_limit_m_s=0.5)
    rig.start_steady(base.top_drive_speed_rad_s, base.hook_load_n)
    rig.advance(2.0)
    rig.command(base.top_drive_speed_rad_s, base.rig.submerged_weight_n * 1.1)
    rig.advance(2.9)
    rig.sample()                                      # WOB and TOB: means since this sample
    rig.advance(0.1)
    s = rig.sample()
    assert s.off_bottom and s.wob_n == 0.0 and s.tob_nm == 0.0
    assert s.rop_m_s == pytest.approx(-0.5)          # rising at the limit, not accelerating
    rig.command(base.top_drive_speed_rad_s, base.hook_load_n)
    rig.advance(20.0)
    s = rig.sample()
    assert not s.off_bottom and s.wob_n > 0           # back down on the rock


def test_failed_steady_start_changes_nothing(base):
    from drill_sim.core import NoSteadyDrilling
    rig = Rig(base.rig)
    rig.start_steady(base.top_drive_speed_rad_s, base.hook_load_n)
    rig.advance(1.0)
    before = (rig.sample(), rig.sim.commands)
    with pytest.raises(NoSteadyDrilling):
        rig.start_steady(1.0, base.rig.submerged_weight_n - 10e3)     # 10 kN < friction weight
    assert (rig.sample(), rig.sim.commands) == before


def _rig_in(base, regime: str) -> Rig:
    """The base rig in stick-slip, or a rig of the base bit in the bouncing regime."""
    if regime == "stick-slip":
        rig = Rig(base.rig)
        rig.start_steady(base.top_drive_speed_rad_s, base.hook_load_n, 1e-3)
        return rig
    params = base.rig.with_groups(Groups(4, 50.0, 2.0, 0.36))
    rig = Rig(params)
    sc = rig.scales
    rig.start_steady(3.0 / sc.time_s, params.submerged_weight_n - 6.0 * sc.force_n, 1e-3)
    return rig


@pytest.mark.parametrize("regime", ["stick-slip", "bouncing"])
def test_parameter_swap_that_keeps_the_physics_changes_nothing(base, regime):
    """replace_parameters with the same values: the run goes on as if nothing happened (the
    depth of cut is measured against the rock surface from before the current pass)."""
    runs = []
    for swap in (False, True):
        rig = _rig_in(base, regime)
        rig.advance(20.0)
        samples = []
        for i in range(300):                       # swaps at many points of the cycle
            if swap and i % 10 == 0:
                rig.replace_parameters(rig.params)
            rig.advance_steps(97)
            s = rig.sample()
            samples.append((s.depth_of_cut_m, s.bit_speed_rad_s, s.rop_m_s, s.wob_n))
        runs.append(np.array(samples))
        if regime == "bouncing":
            assert np.any(runs[-1][:, 0] < 0.0) and np.any(runs[-1][:, 1] == 0.0)
        else:
            assert np.any(runs[-1][:, 1] == 0.0)
    scale = np.max(np.abs(runs[0]), axis=0)
    assert np.max(np.abs(runs[1] - runs[0]) / scale) < 1e-9


def _max_sampled_wob(base, dt_s: float) -> float:
    """Largest WOB of a rig sampled every 1 ms over 15 s of regular stick-slip (100 kN at
    115 rpm on the base rig, where the bit sticks while still moving down)."""
    rig = Rig(base.rig, dt_s=dt_s)
    rig.start_steady(2.5 / rig.scales.time_s, base.rig.submerged_weight_n - 1e5, 1e-3)
    rig.advance(20.0)
    rig.sample()
    best = 0.0
    for i in range(1, 15_001):
        rig.advance_to(20.0 + i * 1e-3)
        best = max(best, rig.sample().wob_n)
    assert rig.metrics()["stick_fraction"] > 0.1
    return best


def test_sampled_wob_of_a_stick_does_not_depend_on_the_step(base):
    """A bit stopped by the rigid rock while moving down takes an impulse within one step
    (per-step WOB w0 + v/(h psi), doubling when dt halves); a sample reports the mean since
    the previous sample, which converges."""
    coarse = _max_sampled_wob(base, 1e-4)
    fine = _max_sampled_wob(base, 5e-5)
    assert coarse > 1.5e5                          # the impulse is there: > 1.5 W0
    assert fine == pytest.approx(coarse, rel=0.02)
    # the offline trajectory reports the same interval means
    rig = Rig(base.rig, dt_s=1e-4)
    rig.start_steady(2.5 / rig.scales.time_s, base.rig.submerged_weight_n - 1e5, 1e-3)
    rig.advance(20.0)
    sc = rig.scales
    tr = rig.sim.run(15.0 / sc.time_s, output_interval=1e-3 / sc.time_s)
    assert np.max(tr.w) * sc.force_n == pytest.approx(coarse, rel=1e-9)


def test_a_sample_without_steps_repeats_the_last_mean(base):
    """Sampling twice at one instant (diagnostics beside the tick) changes nothing; the first
    sample after a start reads the start's own forces."""
    rig = Rig(base.rig)
    rig.start_steady(base.top_drive_speed_rad_s, base.hook_load_n, 1e-3)
    first = rig.sample()
    assert first.wob_n == pytest.approx(1e5, rel=1e-9)
    rig.advance(12.3)
    a = rig.sample()
    assert rig.sample() == a
    rig.replace_parameters(rig.params)
    assert rig.sample().wob_n == pytest.approx(a.wob_n, rel=1e-12)
