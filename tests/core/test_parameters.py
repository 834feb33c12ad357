"""Parameters, scaling and presets: MODEL.md section 8 from geometry; bad input refused."""

from __future__ import annotations

import math

import pytest

from drill_sim.core import Groups, ParameterError, RigParameters, StringGeometry, load_preset
from drill_sim.core.presets import preset_from_dict, preset_names


def test_base_preset_reproduces_the_literature_numbers(base):
    rig, sc, g = base.rig, base.rig.scales, base.rig.groups
    expected = {  # MODEL.md section 8
        "C": (rig.torsional_stiffness_nm_per_rad, 938.0), "I": (rig.bha_inertia_kg_m2, 41.5),
        "M": (rig.bha_mass_kg, 12540.0), "t*": (sc.time_s, 0.21), "L*": (sc.length_m, 2.7e-3),
        "psi": (g.psi, 13.7), "lambda": (g.lam, 6.84), "F*": (sc.force_n, 10.4e3),
    }
    for name, (value, ref) in expected.items():
        assert value == pytest.approx(ref, rel=0.01), name
    assert g.beta == pytest.approx(0.36) and g.n == 4
    assert 1e5 / sc.force_n == pytest.approx(9.6, rel=0.01)          # 100 kN
    assert 2 * math.pi * sc.time_s == pytest.approx(1.32, rel=0.01)   # 60 rpm


def test_submerged_weight_is_the_buoyed_steel_volume(base):
    s = base.string
    steel = (s.steel_density_kg_m3 - s.mud_density_kg_m3) * 9.80665
    area = math.pi / 4 * ((s.pipe_od_m**2 - s.pipe_id_m**2) * s.pipe_length_m
                          + (s.collar_od_m**2 - s.collar_id_m**2) * s.collar_length_m)
    assert base.rig.submerged_weight_n == pytest.approx(steel * area, rel=1e-12)


def test_shipped_presets_differ_only_in_string_length(base):
    assert set(preset_names()) >= {"base", "shallow", "deep"}
    c = base.rig.torsional_stiffness_nm_per_rad
    assert load_preset("shallow").rig.torsional_stiffness_nm_per_rad == pytest.approx(2 * c)
    assert load_preset("deep").rig.torsional_stiffness_nm_per_rad == pytest.approx(c / 3)


def test_long_is_deep_on_the_distributed_string():
    """``long``: the base bit and BHA on 3000 m of the damped pipe, the distributed string by
    default (for on-bottom controller tests); its rig and drive are deep's."""
    long, deep = load_preset("long"), load_preset("deep")
    assert long.string_model == "distributed" and deep.string_model == "lumped"
    assert long.string == deep.string and long.rig == deep.rig
    assert long.top_drive == deep.top_drive
    assert long.string.pipe_length_m == 3000.0 and long.string.torsional_damping_nm_s_per_rad_m > 0


def test_groups_to_si_and_back(base):
    target = Groups(n=3, psi=5.0, lam=3.0, beta=0.5)
    rig = base.rig.with_groups(target)
    g = rig.groups
    assert (g.n, g.psi, g.lam, g.beta) == (3, pytest.approx(5.0), pytest.approx(3.0),
                                           pytest.approx(0.5))


def test_preset_from_yaml_file(tmp_path, base):
    text = (tmp_path / "mine.yaml")
    text.write_text("bit: {bit_radius_m: 0.108, blade_count: 4, intrinsic_specific_energy_pa: 6e7,"
                    " cutting_inclination: 0.6, contact_stress_pa: 6e7, wear_flat_length_m: 0.011,"
                    " friction_coefficient: 0.6, wear_flat_orientation: 1}\n"
                    "lumped: {bha_mass_kg: 12540, bha_inertia_kg_m2: 41.5,"
                    " torsional_stiffness_nm_per_rad: 938, submerged_weight_n: 3.3e5}\n")
    preset = load_preset(text)
    assert preset.name == "mine"
    assert preset.rig.groups.psi == pytest.approx(base.rig.groups.psi, rel=0.01)


GOOD = load_preset("base").rig.as_dict()


@pytest.mark.parametrize("name, value", [
    ("bit_radius_m", math.nan), ("bit_radius_m", -0.1), ("bit_radius_m", 0.0),
    ("intrinsic_specific_energy_pa", math.inf), ("cutting_inclination", "abc"),
    ("bha_mass_kg", None), ("contact_stress_pa", -1.0), ("friction_coefficient", -0.2),
    ("torsional_stiffness_nm_per_rad", -math.inf), ("submerged_weight_n", 0.0),
    ("blade_count", 4.5), ("blade_count", 0), ("blade_count", math.nan), ("blade_count", True),
])
def test_bad_rig_parameter_is_refused_by_name(name, value):
    with pytest.raises(ParameterError) as err:
        RigParameters(**{**GOOD, name: value})
    message = str(err.value)
    assert ("n (blade count)" if name == "blade_count" else name) in message
    assert "expected" in message


@pytest.mark.parametrize("kwargs, name", [
    ({"n": 4, "psi": 0.0, "lam": 1, "beta": 1}, "psi"),
    ({"n": 4, "psi": 1, "lam": -1, "beta": 1}, "lambda"),
    ({"n": 4, "psi": 1, "lam": 1, "beta": math.nan}, "beta"),
    ({"n": 2.5, "psi": 1, "lam": 1, "beta": 1}, "blade count"),
])
def test_bad_group_is_refused_by_name(kwargs, name):
    with pytest.raises(ParameterError, match=name):
        Groups(**kwargs)


def test_bad_string_geometry_is_refused():
    with pytest.raises(ParameterError, match="pipe_id_m"):
        StringGeometry(1000, 0.127, 0.2, 100, 0.15, 0.05)
    with pytest.raises(ParameterError, match="mud_density_kg_m3"):
        StringGeometry(1000, 0.127, 0.1, 100, 0.15, 0.05, mud_density_kg_m3=9000)


@pytest.mark.parametrize("data, fragment", [
    ([1, 2], "expected a mapping"),
    ({"string": {}}, "missing section 'bit'"),
    ({"bit": {"bit_radius_m": 0.1}}, "missing key"),
    ({"bit": {**{k: 1 for k in ("bit_radius_m", "blade_count", "intrinsic_specific_energy_pa",
                                "cutting_inclination", "contact_stress_pa", "wear_flat_length_m",
                                "friction_coefficient", "wear_flat_orientation")}, "color": 1}},
     "unknown key"),
])
def test_bad_preset_is_refused(data, fragment):
    with pytest.raises(ParameterError, match=fragment):
        preset_from_dict("x", data)


def test_missing_and_corrupt_preset_files(tmp_path):
    with pytest.raises(ParameterError, match="neither a shipped preset"):
        load_preset(tmp_path / "nope.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("bit: [unclosed\n")
    with pytest.raises(ParameterError, match="not valid YAML"):
        load_preset(bad)
