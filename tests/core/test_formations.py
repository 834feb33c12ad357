"""Formations along the hole (``well.formations``): the bit cuts the rock of the layer it is
in. Checked against the bit-rock laws written out in SI here (model contract, section 1):
while the bit cuts with its wear flats fully engaged, W = a ζ ε d + a ℓ σ and
T = a² ε d / 2 + μ γ a (a ℓ σ) / 2, d the depth of cut per revolution, with the ε, σ and μ of
the layer the bit is in, step by step across a boundary; a steady start inside a layer is that
layer's steady drilling, V = Ω (W − a ℓ σ) / (2π a ζ ε)."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from drill_sim.core import RPM, ParameterError, load_preset
from drill_sim.core import kernel as kn
from drill_sim.core.presets import well_from_dict
from drill_sim.core.rig import Rig
from drill_sim.core.well import Formation, Well
from drill_sim.session import rules

EPS, SIGMA, MU = "intrinsic_specific_energy_pa", "contact_stress_pa", "friction_coefficient"


@pytest.fixture(scope="module")
def base_preset():
    return load_preset("base")


def _rig(preset, model: str, *layers: Formation) -> Rig:
    geometry = replace(preset.string, well=Well(formations=layers))
    return Rig(preset.rig, string_model=model, geometry=geometry)


def _law_residuals(rig: Rig, rock: dict[str, float]) -> tuple[float, float] | None:
    """(W, T) less the laws' values for ``rock`` [N, N m], relative, or None when the bit is
    not cutting with its wear flats fully engaged (stuck, off bottom, lifting)."""
    x, p, sc = rig.sim.live_state, rig.params, rig.scales
    if rig.sim.regime != kn.REGIME_ROTATING or x[kn.X_G] != 1.0 or x[kn.X_DELTA] <= 0.0:
        return None
    a, zeta, ell, gamma = p.bit_radius_m, p.cutting_inclination, p.wear_flat_length_m, \
        p.wear_flat_orientation
    d = rig.groups.n * x[kn.X_DELTA] * sc.length_m              # per revolution [m]
    wf = a * ell * rock[SIGMA]
    w = x[kn.X_W] * sc.force_n
    t = x[kn.X_T] * sc.stiffness_nm_per_rad
    w_law = a * zeta * rock[EPS] * d + wf
    t_law = a * a * rock[EPS] * d / 2.0 + rock[MU] * gamma * a * wf / 2.0
    return (w - w_law) / w_law, (t - t_law) / t_law


@pytest.mark.parametrize("model", ["lumped", "distributed"])
def test_the_bit_cuts_each_layers_rock_from_the_step_it_enters(base_preset, model):
    """Two layers 1 and 2 cm below the bit's start: ε doubled and σ halved in the first, μ
    in the second (ε and σ then as in the first). Every step, the laws hold with the rock of
    the layer the bit's measured depth is in; no step cuts the wrong rock."""
    start = base_preset.string.length_m
    first = Formation(start + 0.01, intrinsic_specific_energy_pa=120e6, contact_stress_pa=30e6)
    second = Formation(start + 0.02, friction_coefficient=0.9)
    rig = _rig(base_preset, model, first, second)
    p = base_preset.rig
    rig.start_steady(60 * RPM, p.submerged_weight_n - 100e3)
    rocks = {-1: {EPS: p.intrinsic_specific_energy_pa, SIGMA: p.contact_stress_pa,
                  MU: p.friction_coefficient},
             0: {EPS: 120e6, SIGMA: 30e6, MU: p.friction_coefficient},
             1: {EPS: 120e6, SIGMA: 30e6, MU: 0.9}}
    checked = {-1: 0, 0: 0, 1: 0}
    md_before = rig.bit_measured_depth_m
    for _ in range(round(6.0 / rig.dt_s)):
        rig.advance_steps(1)
        md = rig.bit_measured_depth_m
        layer = (md >= first.top_m) + (md >= second.top_m) - 1
        assert rig.layer == layer, f"at {md:.6f} m the bit is in layer {layer}"
        if rig.layer != -1 and md_before < (first.top_m, second.top_m)[rig.layer]:
            md_before = md
            continue          # the step that crossed: cut partly in the layer above
        md_before = md
        residuals = _law_residuals(rig, rocks[rig.layer])
        if residuals is not None:
            assert abs(residuals[0]) < 1e-9 and abs(residuals[1]) < 1e-9
            checked[rig.layer] += 1
    assert min(checked.values()) > 100, checked      # every layer's law seen at work


@pytest.mark.parametrize("model", ["lumped", "distributed"])
def test_a_steady_start_in_a_layer_drills_its_rock(base_preset, model):
    p = base_preset.rig
    layer = Formation(100.0, intrinsic_specific_energy_pa=150e6, contact_stress_pa=90e6,
                      friction_coefficient=0.4)
    rig = _rig(base_preset, model, layer)
    wob, omega = 150e3, 60 * RPM
    rig.start_steady(omega, p.submerged_weight_n - wob)
    assert rig.layer == 0
    s = rig.sample()
    a, zeta, ell = p.bit_radius_m, p.cutting_inclination, p.wear_flat_length_m
    wf = a * ell * 90e6
    assert s.wob_n == pytest.approx(wob, rel=1e-3) if model == "distributed" else \
        s.wob_n == pytest.approx(wob, rel=1e-12)
    rop = omega * (s.wob_n - wf) / (2.0 * math.pi * a * zeta * 150e6)
    assert s.rop_m_s == pytest.approx(rop, rel=1e-9)
    tob = a / (2.0 * zeta) * (s.wob_n - (1.0 - 0.4 * p.wear_flat_orientation * zeta) * wf)
    assert s.tob_nm == pytest.approx(tob, rel=1e-9)


def test_a_run_time_change_holds_until_a_layer_gives_that_value(base_preset):
    """Lumped (the distributed string refuses run-time rock changes): σ changed in layer 0
    holds there; layer 1 gives σ, not ε, so ε stays layer 0's and σ becomes layer 1's."""
    start = base_preset.string.length_m
    rig = _rig(base_preset, "lumped",
               Formation(start - 10.0, intrinsic_specific_energy_pa=80e6),
               Formation(start + 0.01, contact_stress_pa=70e6))
    p = base_preset.rig
    rig.start_steady(60 * RPM, p.submerged_weight_n - 100e3)
    assert (rig.layer, rig.rock[EPS]) == (0, 80e6)
    rig.replace_parameters(replace(p, contact_stress_pa=50e6))
    assert (rig.rock[EPS], rig.rock[SIGMA]) == (80e6, 50e6)
    while rig.layer == 0:
        rig.advance_steps(100)
    assert (rig.layer, rig.rock[EPS], rig.rock[SIGMA]) == (1, 80e6, 70e6)


def test_formations_in_a_preset_and_in_a_bag_record(base_preset):
    well = well_from_dict("x", {"formations": [
        {"top_m": 1200.0, "intrinsic_specific_energy_pa": 1.2e8},
        {"top_m": 1300.0, "contact_stress_pa": 7.0e7, "friction_coefficient": 0.5}]})
    assert well.formations[1].changes() == {SIGMA: 7.0e7, MU: 0.5}
    geometry = replace(base_preset.string, well=well)
    assert rules.geometry_from_record(rules.geometry_record(geometry)) == geometry
    for rows, words in (
            ([{"top_m": 1300.0, MU: 0.5}, {"top_m": 1200.0, MU: 0.4}], "tops increasing"),
            ([{"top_m": 1200.0}], "changes nothing"),
            ([{"top_m": 1200.0, "porosity": 0.2}], "porosity"),
            ([{"top_m": 1200.0, EPS: 1e12}], "out of range"),
            ([{"top_m": float("nan"), MU: 0.5}], "top_m = nan"),
            ("shale at 1200 m", "expected a list of layers")):
        with pytest.raises(ParameterError, match=words):
            well_from_dict("x", {"formations": rows})

