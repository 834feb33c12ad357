"""One YAML loader for every file the package reads (presets, scenarios, sensor profiles):
numbers as YAML 1.2 writes them (``1e9``, ``6e7``, ``-5e-3`` without a dot are floats, where
YAML 1.1's loader made them strings that one reader took and another refused)."""

from __future__ import annotations

from importlib import resources

import pytest

from drill_sim.core import ParameterError, load_preset
from drill_sim.core.resources import load_yaml, read_yaml
from drill_sim.core.sensor_profile import load_profile
from drill_sim.session.scenario import load_scenario


def test_exponent_without_a_dot_is_a_float_and_the_rest_is_yaml_as_before():
    data = load_yaml("a: 1e9\nb: -5e-3\nc: 1.0e9\nd: 12\ne: '1e9'\nf: e9\ng: 1e\nh: 0x10\n")
    assert data == {"a": 1e9, "b": -5e-3, "c": 1e9, "d": 12, "e": "1e9", "f": "e9", "g": "1e",
                    "h": 16}
    assert isinstance(data["a"], float) and isinstance(data["d"], int)


def test_a_preset_a_scenario_and_a_sensor_profile_take_the_same_numbers(tmp_path):
    _, base = read_yaml("preset", "presets", "base")
    assert base["bit"]["intrinsic_specific_energy_pa"] == 60e6          # 60.0e6 in the file
    shipped = (resources.files("drill_sim") / "presets" / "base.yaml").read_text()
    preset = tmp_path / "p.yaml"
    preset.write_text(shipped.replace("intrinsic_specific_energy_pa: 60.0e6",
                                      "intrinsic_specific_energy_pa: 6e7"))
    assert load_preset(preset).rig.intrinsic_specific_energy_pa == 6e7
    profile = tmp_path / "s.yaml"
    profile.write_text("channels:\n  wob_n: {quantum: 1e3, noise_std: 5e2}\n")
    assert load_profile(profile).channels["wob_n"].quantum == 1e3
    scenario = tmp_path / "sc.yaml"
    scenario.write_text("duration_s: 2e1\npoints:\n  - {at_s: 0.0, rpm: 6e1, wob_kn: 1e2}\n")
    assert load_scenario(scenario).duration_s == 20.0


def test_a_quoted_number_in_a_sensor_profile_says_how_to_write_it(tmp_path):
    profile = tmp_path / "s.yaml"
    profile.write_text("channels:\n  wob_n: {quantum: '1e3'}\n")
    with pytest.raises(ParameterError, match=r"written as a YAML number .* not quoted"):
        load_profile(profile)
