"""Strings of several sections (a preset's ``string.sections``): the lumped C, I, M, W_s and
the distributed string's modes of a tapered string of two materials over a BHA of two
sections, against closed forms and an independent transfer-matrix computation in SI; the
two-section keys as a shorthand for two sections, to the last bit; bad sections refused with
the key named; a bag's record of the sections read back exactly."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drill_sim.core import ParameterError, load_preset
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.parameters import GRAVITY_M_S2
from drill_sim.core.presets import preset_from_dict
from drill_sim.core.resources import read_yaml
from drill_sim.core.stability_distributed import string_modes
from drill_sim.core.string_geometry import StringGeometry
from drill_sim.core.top_drive import DriveGroups
from drill_sim.session.rules import geometry_from_record, geometry_record

STEEL = {"G": 77e9, "E": 200e9, "rho": 8000.0}
ALUMINIUM = {"G": 26e9, "E": 70e9, "rho": 2800.0}
# top first: steel pipe, aluminium pipe, then two BHA sections (the lower one heavier)
SECTIONS = [
    {"length_m": 600.0, "od_m": 0.127, "id_m": 0.108},
    {"length_m": 500.0, "od_m": 0.147, "id_m": 0.121, "shear_modulus_pa": ALUMINIUM["G"],
     "young_modulus_pa": ALUMINIUM["E"], "steel_density_kg_m3": ALUMINIUM["rho"]},
    {"length_m": 60.0, "od_m": 0.1524, "id_m": 0.0572, "bha": True},
    {"length_m": 40.0, "od_m": 0.2032, "id_m": 0.0714, "bha": True},
]


def _tapered(**string):
    _name, data = read_yaml("preset", "presets", "base")
    keep = {k: v for k, v in data["string"].items() if not k.startswith(("pipe_", "collar_"))}
    keep.update(torsional_damping_nm_s_per_rad_m=0.0, axial_damping_n_s_per_m2=0.0,
                torsional_retardation_time_s=0.0, axial_retardation_time_s=0.0)
    return preset_from_dict("tapered", {**data, "string": {**keep, "sections": SECTIONS,
                                                             **string}})


def _j(s):
    return math.pi / 32.0 * (s["od_m"] ** 4 - s["id_m"] ** 4)


def _a(s):
    return math.pi / 4.0 * (s["od_m"] ** 2 - s["id_m"] ** 2)


def _material(s):
    return ALUMINIUM if "shear_modulus_pa" in s else STEEL


def test_lumped_figures_of_a_tapered_string_are_the_closed_forms():
    """C = 1/sum(L/(G J)) over the pipe, I = sum(rho J L) and M = sum(rho A L) over the BHA,
    W_s = sum((rho - rho_mud) g A L) over the whole string, each section with its material."""
    rig = _tapered().rig
    pipe, bha = SECTIONS[:2], SECTIONS[2:]
    c = 1.0 / sum(s["length_m"] / (_material(s)["G"] * _j(s)) for s in pipe)
    inertia = sum(_material(s)["rho"] * _j(s) * s["length_m"] for s in bha)
    mass = sum(_material(s)["rho"] * _a(s) * s["length_m"] for s in bha)
    weight = sum((_material(s)["rho"] - 1200.0) * GRAVITY_M_S2 * _a(s) * s["length_m"]
                 for s in SECTIONS)
    assert rig.torsional_stiffness_nm_per_rad == pytest.approx(c, rel=1e-12)
    assert rig.bha_inertia_kg_m2 == pytest.approx(inertia, rel=1e-12)
    assert rig.bha_mass_kg == pytest.approx(mass, rel=1e-12)
    assert rig.submerged_weight_n == pytest.approx(weight, rel=1e-12)


def _held_top_frequencies(kind: str, bha_end: float, count: int) -> list[float]:
    """The lossless tapered pipe's angular frequencies [rad/s], top held (torsion) or free
    (axial), the BHA's inertia or mass at the bottom: the SI transfer matrices of (x, F) per
    section, [[cos kL, sin kL/(K k)], [-K k sin kL, cos kL]], k = w sqrt(m/K), multiplied top
    to bottom; the end condition's sign changes on a fine grid, refined by bisection."""
    def f(w):
        m = np.array([[1.0, 0.0], [0.0, 1.0]])
        for s in SECTIONS[:2]:
            mat = _material(s)
            prop = _j(s) if kind == "torsion" else _a(s)
            stiff = (mat["G"] if kind == "torsion" else mat["E"]) * prop
            k = w * math.sqrt(mat["rho"] * prop / stiff)
            kl = k * s["length_m"]
            sec = np.array([[math.cos(kl), math.sin(kl) / (stiff * k)],
                            [-stiff * k * math.sin(kl), math.cos(kl)]])
            m = sec @ m
        # x(0), F(0): torsion x(0) = 0 (held), F(0) = 1; axial F(0) = 0 (free), x(0) = 1;
        # bottom: the BHA's end - F(L) = -end w^2 x(L) (x'' = -w^2 x), i.e. F(L) = end w^2 x(L)
        top = np.array([0.0, 1.0]) if kind == "torsion" else np.array([1.0, 0.0])
        x, force = m @ top
        return force - bha_end * w * w * x
    ws = np.linspace(1e-3, 120.0, 120_001)
    values = np.array([f(w) for w in ws])
    roots = []
    for i in np.nonzero(np.sign(values[1:]) != np.sign(values[:-1]))[0]:
        lo, hi = ws[i], ws[i + 1]
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if np.sign(f(mid)) == np.sign(f(lo)) else (lo, mid)
        roots.append(0.5 * (lo + hi))
    return roots[:count]


@pytest.mark.slow("the taper's modes by a transfer-matrix product on a fine frequency grid: ~4 s")
def test_modes_of_a_tapered_string_are_its_transfer_matrices_in_si():
    """The distributed string's lossless modes (top held, bit off bottom) on two pipe sections
    of two materials: the roots of an independent SI transfer-matrix product (1e-7), and the
    waves' travel time the sum of the sections' L/c (1e-12)."""
    p = _tapered()
    ts = p.rig.scales.time_s
    res = string_modes(geometry_waves(p.rig, p.string, 5e-4, continuous=True),
                       p.rig.groups.psi, DriveGroups(), count=4)
    assert res.complete
    for kind, found, end in (("torsion", res.torsional, p.rig.bha_inertia_kg_m2),
                             ("axial", res.axial, p.rig.bha_mass_kg)):
        expected = _held_top_frequencies(kind, end, 4)
        assert [m.root.real for m in found] == pytest.approx([0.0] * 4, abs=1e-9)
        assert [m.frequency / ts for m in found] == pytest.approx(expected, rel=1e-7), kind
    waves = geometry_waves(p.rig, p.string, 5e-4)
    travel = sum(s["length_m"] / math.sqrt(_material(s)["G"] / _material(s)["rho"])
                 for s in SECTIONS[:2])
    assert float(np.sum(waves.torsion.delay)) * ts == pytest.approx(travel, rel=1e-12)


def test_two_section_keys_are_a_shorthand_for_two_sections():
    """base's pipe over collars and the same as ``sections``: the same rig, the same wave
    lines, to the last bit."""
    p = load_preset("base")
    g = p.string
    name, data = read_yaml("preset", "presets", "base")
    string = {k: v for k, v in data["string"].items() if not k.startswith(("pipe_", "collar_"))}
    string["sections"] = [
        {"length_m": g.pipe_length_m, "od_m": g.pipe_od_m, "id_m": g.pipe_id_m},
        {"length_m": g.collar_length_m, "od_m": g.collar_od_m, "id_m": g.collar_id_m,
         "bha": True}]
    q = preset_from_dict(name, {**data, "string": string})
    assert q.rig == p.rig
    assert q.top_drive == p.top_drive                 # the default K_p = 50 Z of the top pipe
    a, b = geometry_waves(p.rig, p.string, 5e-4), geometry_waves(q.rig, q.string, 5e-4)
    for x, y in ((a.torsion, b.torsion), (a.axial, b.axial)):
        for field in ("z", "delay", "steps", "frac", "dashpot", "relative", "tau"):
            assert np.array_equal(getattr(x, field), getattr(y, field)), field


@pytest.mark.parametrize("change, words", [
    ({"sections": [SECTIONS[2], SECTIONS[0]]}, "pipe's sections first"),
    ({"sections": SECTIONS[:2]}, "at least one) after them"),
    ({"sections": []}, "string.sections is an empty list: expected a list of at least two"),
    ({"sections": {"length_m": 1.0}}, "string.sections is dict: expected a list"),
    ({"sections": [{**SECTIONS[0], "od_m": -1.0}, SECTIONS[2]]}, "string.sections[0]: od_m"),
    ({"sections": [{**SECTIONS[0], "id_m": 0.2}, SECTIONS[2]]}, "id_m = 0.2"),
    ({"sections": [{**SECTIONS[0], "bha": "yes"}, SECTIONS[2]]}, "bha = 'yes'"),
    ({"sections": [{"length_m": 1.0, "od_m": 0.1}, SECTIONS[2]]}, "missing key(s) ['id_m']"),
    ({"sections": [{**SECTIONS[0], "colour": 1}, SECTIONS[2]]}, "unknown key(s) ['colour']"),
    ({"sections": [{**SECTIONS[0], "shear_modulus_pa": math.nan}, SECTIONS[2]]},
     "shear_modulus_pa"),
    ({"pipe_length_m": 1000.0}, "pipe_length_m with sections"),
])
def test_bad_sections_are_refused_naming_what_is_wrong(change, words):
    with pytest.raises(ParameterError) as info:
        _tapered(**change)
    assert words in str(info.value)
    assert "tapered" in str(info.value)


def test_a_strings_sections_go_into_a_bags_record_and_back_exactly():
    g = _tapered().string
    record = geometry_record(g)
    assert all(isinstance(v, str) for v in record.values())
    assert geometry_from_record(record) == g
    assert geometry_from_record(geometry_record(load_preset("base").string)) == \
        load_preset("base").string
    with pytest.raises(ParameterError, match="not a pipe geometry"):
        geometry_from_record({**record, "sections": "[{\"length_m\": 1}]"})


def test_a_geometry_without_its_sections_or_keys_is_refused():
    with pytest.raises(ParameterError, match="pipe_length_m is missing"):
        StringGeometry()
