"""What the core refuses, and why: steps that cannot resolve the model, stability queries out of
their range. Each refusal is a ParameterError that says what would work."""

from __future__ import annotations

import math
import time
from dataclasses import replace

import pytest

from drill_sim.core import Groups, ParameterError, Rig, Simulator
from drill_sim.core.resolution import max_step
from drill_sim.core.stability import stability

STIFF = Groups(4, 1e4, 6.84, 0.36)          # axial period 2 pi/sqrt(4e4) = 0.031 t*


def _stick_and_rop(groups: Groups, dt: float) -> tuple[float, float]:
    sim = Simulator(groups, dt)
    sim.start_steady(9.6, 1.32, 1e-3)
    sim.run(50.0)
    sim.reset_window()
    m = sim.run(50.0).metrics
    return m.stick_fraction, m.mean_rop


def test_a_step_that_cannot_resolve_the_axial_mode_is_refused():
    """psi = 1e4 at dt = 0.05 used to stick for good where a resolving step never sticks."""
    with pytest.raises(ParameterError, match="cannot resolve the fastest mode"):
        Simulator(STIFF, 0.05)
    with pytest.raises(ParameterError, match=r"dt <= 0.00157"):
        Simulator(STIFF, 2 * max_step(STIFF))
    assert max_step(STIFF) == pytest.approx(2 * math.pi / 200 / 20)
    # at the limit the answer is the fine step's: no stick, the same rate of penetration (within
    # 5 %: this regime's mean ROP settles at 1.087 or 1.113 depending on the step, two states)
    stick, rop = _stick_and_rop(STIFF, max_step(STIFF))
    fine_stick, fine_rop = _stick_and_rop(STIFF, max_step(STIFF) / 4)
    assert stick == fine_stick == 0.0
    assert rop == pytest.approx(fine_rop, rel=0.05)


def test_the_rig_refuses_a_step_too_coarse_for_new_parameters(base):
    rig = Rig(base.rig, dt_s=2e-3)                 # fine for base: limit ~ 8.9 ms
    rig.start_steady(base.top_drive_speed_rad_s, base.hook_load_n)
    rig.advance(0.5)
    before = rig.sample()
    heavy = replace(base.rig, bha_mass_kg=base.rig.bha_mass_kg / 100)     # psi x 100
    with pytest.raises(ParameterError, match=r"dt_s = 0.002 s cannot resolve"):
        rig.replace_parameters(heavy)
    assert rig.params == base.rig and rig.sample() == before
    with pytest.raises(ParameterError, match="cannot resolve"):
        Rig(heavy, dt_s=2e-3)


BASE = Groups(4, 13.73, 6.84, 0.36)


@pytest.mark.parametrize("omega0", [1e-3, 1e-4, 1e-9])
def test_stability_at_very_low_speed_is_refused_with_the_speed_that_works(omega0):
    """Used to raise OverflowError (exp(-re_min tau_n0) with tau_n0 = 2 pi/(n omega0))."""
    t0 = time.perf_counter()
    with pytest.raises(ParameterError, match=r"too low for the root search.*omega0 >= 0.038"):
        stability(BASE, 9.6, omega0)
    assert time.perf_counter() - t0 < 1.0
    with pytest.raises(ParameterError, match="re_min >="):        # just below: refused
        stability(BASE, 9.6, 0.0379, re_min=-1e-3)
    # 0.038 itself is accepted (searching it takes a few seconds: 137 roots, complete)


def test_stability_box_too_wide_for_the_delay_is_refused_with_the_re_min_that_works():
    """omega0 = 0.1 with the default re_min = -0.5 asked for ~2000 roots (24 s, incomplete)."""
    with pytest.raises(ParameterError, match=r"use re_min >= -0.165"):
        stability(BASE, 9.6, 0.1)
    res = stability(BASE, 9.6, 0.1, re_min=-0.165)
    assert res.complete and not res.stable
    assert res.rightmost.real == pytest.approx(0.17697, abs=1e-5)


@pytest.mark.parametrize("re_min", [-1000.0, -1e308, -6.6])
def test_absurd_re_min_is_refused_at_once(re_min):
    t0 = time.perf_counter()
    with pytest.raises(ParameterError, match=r"use re_min >= -6.5"):
        stability(BASE, 9.6, 1.32, re_min=re_min)
    assert time.perf_counter() - t0 < 1.0
    with pytest.raises(ParameterError, match="re_min"):
        stability(BASE, 9.6, 1.32, re_min=-math.inf)


def test_a_step_turning_the_bit_over_a_sector_is_refused_not_swept_wrongly():
    """w0 = 1e5 winds the string up so far that the bit slips at ~1e5 / t*, 30 sectors a step
    at the default dt: the sweep used to keep only the last sector's nodes, silently."""
    sim = Simulator(BASE)
    sim.start_steady(1e5, 1.32, 1e-3)
    with pytest.raises(ParameterError, match="more than a sector"):
        sim.run(20.0)
    s = sim.state()
    assert 0.0 < s.tau < 20.0 and sim.steps == round(s.tau / sim.dt)
    assert math.isfinite(s.omega) and math.isfinite(s.u)
    with pytest.raises(ParameterError, match="more than a sector"):
        sim.advance(10)                                   # and again, not one step further
    assert sim.state() == s
    # w0 = 1e3 slips at ~900 / t*, 0.28 sector a step: accepted
    ok = Simulator(BASE)
    ok.start_steady(1e3, 1.32, 1e-3)
    assert ok.run(20.0).metrics.stick_fraction > 0.5
    with pytest.raises(ParameterError, match="omega0"):  # a command that would do it at once
        ok.set_commands(10.0, 1.01 * 2 * math.pi / BASE.n / ok.dt)
