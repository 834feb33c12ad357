"""The one declaration of the rig's state (``core/state_layout``): the kernels' constants are
its tables, every unit scales to SI as the model contract's scales say, a saved state resumes
bit for bit on both string models, and what cannot be loaded is refused."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drill_sim.core import distributed_kernel as dk
from drill_sim.core import kernel as kn
from drill_sim.core import state_layout as sl
from drill_sim.core.parameters import ParameterError, Scales
from drill_sim.core.presets import load_preset
from drill_sim.core.rig import Rig
from drill_sim.core.rig_sample import RPM
from drill_sim.core.top_drive import TopDriveParameters


def test_the_kernels_constants_are_the_declarations_indices():
    for block in sl.BLOCKS:
        for i, slot in enumerate(block.slots):
            assert getattr(sl, f"{block.prefix}_{slot.key}") == i
        lumped = block.of(sl.LUMPED)
        assert all(s.model == sl.LUMPED for s in lumped)
        assert all(s.model == sl.DISTRIBUTED for s in block.slots[len(lumped):])
        assert getattr(sl, f"N{block.prefix}") == len(lumped)
        assert getattr(sl, f"N{block.prefix}D") == len(block.slots)
    # the kernels compile these very numbers
    for module in (kn, dk):
        for name, value in vars(module).items():
            if name[:2] in ("X_", "K_", "P_", "C_", "A_", "O_") and hasattr(sl, name):
                assert value == getattr(sl, name), name


def _rig(model: str, preset: str = "base", mode: str = "kinematic") -> Rig:
    p = load_preset(preset)
    drive = p.top_drive if mode == "kinematic" else TopDriveParameters(
        top_drive_mode=mode, drive_kp_nm_s_rad=p.top_drive.drive_kp_nm_s_rad or 3e4)
    rig = Rig(p.rig, string_model=model, geometry=p.string, top_drive=drive)
    rig.start_steady(60 * RPM, p.rig.submerged_weight_n - 100e3, 0.01)
    return rig


@pytest.mark.parametrize("model", [sl.LUMPED, sl.DISTRIBUTED])
def test_each_array_holds_its_models_slots(model):
    sim = _rig(model).sim
    assert sim.MODEL == model
    for name, block in (("x", sl.STATE), ("k", sl.COUNTS), ("p", sl.PARAMETERS),
                        ("c", sl.COMMANDS), ("acc", sl.WINDOW)):
        assert sim.arrays()[name].size == block.size(model)


def _si(unit: sl.Dimension, sc: Scales) -> float:
    """SI per unit, written out from the model contract's scales (section 3)."""
    return {"-": 1.0, "t*": sc.time_s, "1/t*": 1.0 / sc.time_s, "1/t*^2": sc.time_s ** -2,
            "L*": sc.length_m, "L*/t*": sc.length_m / sc.time_s,
            "L*/t*^2": sc.length_m / sc.time_s ** 2, "C": sc.stiffness_nm_per_rad,
            "F*": sc.force_n, "C/t*": sc.stiffness_nm_per_rad / sc.time_s,
            "C t*": sc.stiffness_nm_per_rad * sc.time_s, "F* L*": sc.force_n * sc.length_m,
            "F* t*": sc.force_n * sc.time_s, "I": 1.0}[unit.symbol]


def test_every_unit_carries_the_same_si_quantity_to_other_scales():
    """A slot rescaled from one rig's scales to another's is the same SI quantity: a unit
    rescaled the wrong way round (omega by t*_old/t*_new) or by the wrong scale fails."""
    old = Scales(time_s=0.31, length_m=2.1e-3, force_n=5.3e4, stiffness_nm_per_rad=1.7e4)
    new = Scales(time_s=0.77, length_m=6.2e-4, force_n=1.9e5, stiffness_nm_per_rad=3.3e3)
    units = {s.unit for block in sl.BLOCKS for s in block.slots} - {sl.INERTIA}
    for unit in units:
        assert unit.si_factor(old) == pytest.approx(_si(unit, old), rel=1e-14), unit
        value = 1.234
        carried = unit.rescale(value, old, new)
        assert carried * _si(unit, new) == pytest.approx(value * _si(unit, old), rel=1e-14), unit


def _run(sim, steps: int) -> np.ndarray:
    out = np.empty((steps // 10, sl.OUTPUTS.size(sim.MODEL)))
    sim.start_sample()
    rows = sim.advance_into(steps, out, 10, 0)
    return out[:rows]


def _starting_up(rig: Rig) -> None:
    """Off bottom at rest, then the top drive turned at 60 rpm: the wall's stations break
    loose one after another down the hole."""
    rig.start_at_rest(0.5)
    rig.command(60 * RPM, rig.params.submerged_weight_n)


@pytest.mark.parametrize("model, preset, mode, start", [
    (sl.LUMPED, "base", "speed", None), (sl.DISTRIBUTED, "base", "kinematic", None),
    (sl.DISTRIBUTED, "field_a", "speed", _starting_up)])
def test_a_saved_state_resumes_bit_for_bit(model, preset, mode, start):
    """save_state, run, load_state, run again: the same rows to the bit (the wall's contact
    forces and held stations, the lines' waves and low-passes included); and into a second
    simulator built alike."""
    rig = _rig(model, preset, mode)
    if start is not None:
        start(rig)
    sim = rig.sim
    sim.advance(20_000)                       # into stick-slip, or the wall breaking loose
    if start is not None:
        assert 0 < np.count_nonzero(sim.wall_held) < sim.wall_held.size - 1
    saved = sim.save_state()
    first = _run(sim, 30_000)
    sim.load_state(saved)
    again = _run(sim, 30_000)
    assert np.array_equal(first, again)
    other = _rig(model, preset, mode)
    if start is not None:
        start(other)
    other = other.sim
    other.load_state(saved)
    assert np.array_equal(first, _run(other, 30_000))
    assert not np.array_equal(saved.arrays["x"], sim.save_state().arrays["x"])   # it moved


def test_a_state_of_another_model_or_shape_is_refused_and_changes_nothing():
    lumped, distributed = _rig(sl.LUMPED).sim, _rig(sl.DISTRIBUTED).sim
    before = distributed.save_state()
    with pytest.raises(ParameterError, match="lumped state of another shape"):
        distributed.load_state(lumped.save_state())
    for name, array in before.arrays.items():
        assert np.array_equal(array, distributed.arrays()[name])
    with pytest.raises(ParameterError, match="wave buffers"):
        distributed.place(distributed.state(), steps=0,
                          surface=distributed.surface)


def test_a_view_carried_to_new_scales_keeps_its_si_values():
    """Rig.replace_parameters places the state rescaled slot by slot: every field of the
    view is the same SI quantity after the swap (the twist, the speeds, the motor's torque)."""
    rig = _rig(sl.LUMPED, "base", "speed")
    rig.advance(5.0)
    old = rig.scales
    view = rig.sim.state()
    p = rig.params
    rig.replace_parameters(type(p)(**{**p.as_dict(), "intrinsic_specific_energy_pa":
                                      1.3 * p.intrinsic_specific_energy_pa}))
    new, carried = rig.scales, rig.sim.state()
    assert new.length_m != old.length_m
    for name, i in ((n, sl.STATE.index(n)) for n in ("u", "v", "omega", "since_stick",
                                                     "motor_torque", "drive_integral", "w")):
        unit = sl.STATE.slots[i].unit
        assert getattr(carried, name) * _si(unit, new) == pytest.approx(
            getattr(view, name) * _si(unit, old), rel=1e-13, abs=1e-300), name
    assert carried.phi == view.phi and carried.phi_td == view.phi_td
    assert math.isclose(rig.sim.tau * new.time_s, view.tau * old.time_s, rel_tol=1e-13)
