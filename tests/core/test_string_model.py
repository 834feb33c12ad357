"""Choosing the string model: the preset key, ``Rig(string_model=...)`` and its limits."""

from __future__ import annotations

import pytest

from drill_sim.core import ParameterError, Rig, load_preset
from drill_sim.core.distributed_simulator import StringSimulator
from drill_sim.core.presets import preset_from_dict
from drill_sim.core.resources import read_yaml


def _base_dict() -> dict:
    return dict(read_yaml("preset", "presets", "base")[1])


def test_preset_key_is_optional_and_checked():
    assert load_preset("base").string_model == "lumped"
    data = _base_dict()
    assert preset_from_dict("x", {**data, "string_model": "distributed"}).string_model == \
        "distributed"
    with pytest.raises(ParameterError, match="string_model"):
        preset_from_dict("x", {**data, "string_model": "rope"})
    lumped = {k: v for k, v in data.items() if k != "string"}
    lumped["lumped"] = load_preset("base").string.lumped()
    with pytest.raises(ParameterError, match="needs a 'string' section"):
        preset_from_dict("x", {**lumped, "string_model": "distributed"})


def test_distributed_rig_keeps_the_si_face():
    """The same calls on both models; <Omega> = Omega0 within 1 % over 100 s of stick-slip,
    and the stick fraction differs from the lumped model's."""
    p = load_preset("base")
    stick = {}
    for model in ("lumped", "distributed"):
        rig = Rig(p.rig, string_model=model, geometry=p.string)
        assert isinstance(rig.sim, StringSimulator) == (model == "distributed")
        rig.start_steady(p.top_drive_speed_rad_s, p.hook_load_n, perturbation=1e-3)
        rig.advance(30.0)
        rig.reset_metrics_window()
        rig.advance(100.0)
        sample = rig.sample()
        assert sample.time_s == pytest.approx(130.0, abs=rig.dt_s)
        m = rig.metrics()
        assert m["mean_bit_speed_rad_s"] == pytest.approx(p.top_drive_speed_rad_s, rel=1e-2)
        stick[model] = m["stick_fraction"]
    assert abs(stick["distributed"] - stick["lumped"]) > 0.1
    rig.start_at_rest(1.0)
    assert rig.sample().off_bottom


def test_distributed_rig_needs_geometry_and_refuses_replace_parameters():
    p = load_preset("base")
    with pytest.raises(ParameterError, match="needs geometry"):
        Rig(p.rig, string_model="distributed")
    with pytest.raises(ParameterError, match="string model"):
        Rig(p.rig, string_model="rope")
    rig = Rig(p.rig, string_model="distributed", geometry=p.string)
    rig.start_steady(p.top_drive_speed_rad_s, p.hook_load_n)
    with pytest.raises(ParameterError, match="replace_parameters: not available"):
        rig.replace_parameters(p.rig)
