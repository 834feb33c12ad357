"""The hook as a position boundary (``hook_mode`` position): the drawworks hold or move the
block and the hook load is measured. Checked against the statics of the string, computed here
from the preset's pipe alone: with the block held the WOB falls by the pipe's axial stiffness
times the bit's advance and the hook takes what the bit gives up; with the block lowered the bit
drills at the block's speed on average."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drill_sim.core import RPM, ParameterError, load_preset
from drill_sim.core.rig import Rig
from drill_sim.session import rules
from drill_sim.session.parameter_table import specs


@pytest.fixture(scope="module")
def base_preset():
    return load_preset("base")


def _axial_stiffness_n_m(preset) -> float:
    """K_a of the pipe above the rigid BHA, from its outer and inner diameters and E."""
    g = preset.string
    area = math.pi / 4.0 * (g.pipe_od_m ** 2 - g.pipe_id_m ** 2)
    return g.young_modulus_pa * area / g.pipe_length_m


def _run(preset, block_speed_m_s: float, seconds: float) -> dict[str, np.ndarray]:
    p = preset.rig
    rig = Rig(p, string_model="distributed", geometry=preset.string)
    rig.start_steady(120 * RPM, p.submerged_weight_n - 130e3)
    rig.set_hook_mode("position", block_speed_m_s)
    steps = round(1e-3 / rig.dt_s)
    rows = []
    for _ in range(round(seconds * 1e3)):
        rig.advance_steps(steps)
        s = rig.sample()
        rows.append((s.time_s, s.wob_n, s.hook_load_n, s.bit_depth_m, s.rop_m_s))
    t, w, h, u, v = np.array(rows).T
    return {"t": t, "wob": w, "hook": h, "u": u, "v": v}


def test_held_block_drills_off_the_strings_stretch(base_preset):
    """ΔW = K_a Δu and H + W = W_s: the top held still (a force boundary would keep W and
    let the top follow: ΔW ≈ 0), the axial stiffness the pipe's."""
    r = _run(base_preset, 0.0, 18.5)
    ka = _axial_stiffness_n_m(base_preset)

    def mean(x, t0):
        window = (r["t"] >= t0) & (r["t"] < t0 + 1.0)
        return float(np.mean(x[window]))

    for t0, t1 in ((1.0, 5.0), (2.0, 10.0), (1.0, 17.0)):
        drop = mean(r["wob"], t0) - mean(r["wob"], t1)
        advance = mean(r["u"], t1) - mean(r["u"], t0)
        assert drop > 4e3
        assert drop == pytest.approx(ka * advance, rel=0.03)
    ws = base_preset.rig.submerged_weight_n
    for t0 in (1.0, 9.0, 17.0):
        assert mean(r["hook"], t0) + mean(r["wob"], t0) == pytest.approx(ws, rel=3e-3)
    # it drills off towards the wear flats' weight a l sigma, where cutting stops
    assert mean(r["wob"], 17.0) == pytest.approx(base_preset.rig.friction_weight_n, rel=0.01)


def test_lowered_block_sets_the_drill_rate(base_preset):
    r = _run(base_preset, 5e-3, 40.0)
    last = r["t"] > 30.0
    assert float(np.mean(r["v"][last])) == pytest.approx(5e-3, rel=0.01)


def test_position_mode_needs_the_distributed_string(base_preset):
    rig = Rig(base_preset.rig)
    with pytest.raises(ParameterError, match="needs string_model = 'distributed'"):
        rig.set_hook_mode("position")
    with pytest.raises(ParameterError, match="hook_mode = 'sideways': expected one of force, "
                                             "position"):
        rig.set_hook_mode("sideways")
    assert rig.hook_mode == "force"
    rig = Rig(base_preset.rig, string_model="distributed", geometry=base_preset.string)
    for bad in (float("nan"), float("inf"), 11.0):
        with pytest.raises(ParameterError, match="block_speed_m_s = "):
            rig.set_hook_mode("position", bad)
    assert (rig.hook_mode, rig.sim.hook_position) == ("force", False)     # unchanged


def test_back_to_force_holds_the_load_measured_then(base_preset):
    """Bumpless: the hook load the sample shows does not jump at the switch back, and the hook
    then holds it (the old command, 130 kN of WOB, is not restored)."""
    p = base_preset.rig
    rig = Rig(p, string_model="distributed", geometry=base_preset.string)
    rig.start_steady(120 * RPM, p.submerged_weight_n - 130e3)
    rig.set_hook_mode("position", 0.0)
    rig.advance_steps(round(3.0 / rig.dt_s))
    before = rig.sample().hook_load_n
    assert before > p.submerged_weight_n - 125e3           # the bit gave up weight
    rig.set_hook_mode("force")
    assert rig.sample().hook_load_n == pytest.approx(before, abs=1e-6)
    assert rig.commanded_hook_load_n == pytest.approx(before, abs=1e-6)
    rig.advance_steps(round(0.5 / rig.dt_s))
    assert rig.sample().hook_load_n == pytest.approx(before, abs=1e-6)


def test_session_parameters_reach_the_rig(base_preset):
    """``hook_mode`` and ``block_speed_m_s`` through the session's rules: at start, changed at
    run time, and a refused change leaves the rig as it was."""
    p = {s.name: s.default for s in specs(base_preset)}
    p.update(string_model="distributed", hook_mode="position", block_speed_m_s=0.002)
    rig = rules.make_rig(p, geometry=base_preset.string)
    assert (rig.hook_mode, rig.block_speed_m_s) == ("position", 0.002)
    new = dict(p, block_speed_m_s=0.0)
    assert rules.apply_changes(rig, p, new) == {"block_speed_m_s"}
    assert rig.block_speed_m_s == 0.0
    lumped = dict(p, string_model="lumped", hook_mode="force")
    rig = rules.make_rig(lumped)
    with pytest.raises(ParameterError, match="needs string_model"):
        rules.apply_changes(rig, lumped, dict(lumped, hook_mode="position",
                                              initial_top_drive_speed_rad_s=1.0))
    assert rig.hook_mode == "force"
