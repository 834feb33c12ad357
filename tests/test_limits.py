"""What the core refuses, and why: steps that cannot resolve the model, stability queries out of
their range. Each refusal is a ParameterError that says what would work."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from drill_sim.core import Groups, ParameterError, Rig, Simulator
from drill_sim.core.simulator import max_step

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
    # at the limit the answer is the fine step's: no stick, the same rate of penetration
    stick, rop = _stick_and_rop(STIFF, max_step(STIFF))
    fine_stick, fine_rop = _stick_and_rop(STIFF, max_step(STIFF) / 4)
    assert stick == fine_stick == 0.0
    assert rop == pytest.approx(fine_rop, rel=0.01)


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
