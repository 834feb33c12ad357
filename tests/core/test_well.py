"""A deviated hole with friction along the string (a preset's ``well``): the survey's geometry
(minimum curvature), W_s along the hole's axis and the soft string's wall force against closed
forms; the break-off torque of a slant well against mu g (rho - rho_mud) A r L sin(incl); the
energy balance with the wall's dissipation; friction off gives the string without a wall,
exactly; a steady start is an equilibrium against the wall; bad wells refused by name."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from pipe_theory import energy_ledger, lossless_string

from drill_sim.core import ParameterError, load_preset
from drill_sim.core import distributed_kernel as dk
from drill_sim.core import kernel as kn
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.distributed_simulator import StringSimulator
from drill_sim.core.parameters import GRAVITY_M_S2, RigParameters
from drill_sim.core.presets import preset_from_dict
from drill_sim.core.resources import read_yaml
from drill_sim.core.well import Well
from drill_sim.session.rules import geometry_from_record, geometry_record

H = 5e-4
SLANT = ((0.0, 30.0, 0.0), (2000.0, 30.0, 0.0))
# vertical to 300 m, built at a constant rate to 40 deg at 700 m (azimuth 0), then straight
BUILD = ((0.0, 0.0, 0.0), (300.0, 0.0, 0.0), (700.0, 40.0, 0.0), (1200.0, 40.0, 0.0))


def _rig(geometry):
    p = load_preset("base")
    params = RigParameters(**{**p.rig.as_dict(), **geometry.lumped()})
    return p, params


def _w(geometry, part):
    steel, mud = geometry.steel_density_kg_m3, geometry.mud_density_kg_m3
    return (steel - mud) * GRAVITY_M_S2 * math.pi / 4 * (part.od_m**2 - part.id_m**2)


def test_submerged_weight_is_the_weight_along_the_holes_axis():
    """Slant: W_s cos(30 deg); a planar build (inclination linear in measured depth):
    integral cos = (sin i1 - sin i0)/k over the arc, k its curvature (1e-9)."""
    g = load_preset("base").string
    vertical = g.lumped()["submerged_weight_n"]
    slant = replace(g, well=Well(SLANT)).lumped()["submerged_weight_n"]
    assert slant == pytest.approx(vertical * math.cos(math.radians(30.0)), rel=1e-12)
    built = replace(g, well=Well(BUILD)).lumped()["submerged_weight_n"]
    pipe, collar = g.parts()
    k = math.radians(40.0) / 400.0
    def axis(a: float, b: float) -> float:
        """The length of [a, b] measured depth projected on the vertical."""
        vertical = max(0.0, min(b, 300.0) - a)
        s0, s1 = max(a, 300.0), min(b, 700.0)
        arc = (math.sin(k * (s1 - 300.0)) - math.sin(k * (s0 - 300.0))) / k if s1 > s0 else 0.0
        return vertical + arc + max(0.0, b - max(a, 700.0)) * math.cos(math.radians(40.0))

    expected = _w(g, pipe) * axis(0.0, 1000.0) + _w(g, collar) * axis(1000.0, 1100.0)
    assert built == pytest.approx(expected, rel=1e-9)


def test_wall_force_is_the_soft_strings():
    """Straight and inclined: n = w sin(incl); in the build, in its vertical plane, the
    tension pulls the string to the inside of the bend and the weight to the low side:
    n = |T k - w sin(incl)|, T the buoyed weight hanging below along the axis (1e-9)."""
    g = load_preset("base").string
    pipe = g.parts()[0]
    slant = replace(g, well=Well(SLANT))
    assert slant.wall_forces_n_m(0, [0.1, 0.5, 0.9]) == pytest.approx(
        [_w(g, pipe) * 0.5] * 3, rel=1e-12)
    built = replace(g, well=Well(BUILD))
    k = math.radians(40.0) / 400.0
    for f in (0.35, 0.5, 0.65):
        md = 1000.0 * f                                    # in the build (300 to 700 m)
        incl = k * (md - 300.0)
        tension = built.hanging_tension_n(md)
        expected = abs(tension * k - _w(g, pipe) * math.sin(incl))
        assert built.wall_forces_n_m(0, [f])[0] == pytest.approx(expected, rel=1e-9), f
    assert built.wall_forces_n_m(0, [0.2]) == [0.0]       # vertical: no wall force


def _turned_slowly(mu_s, mu_d, duration=800.0):
    """Base's lossless pipe in the slant well, off bottom, the top turned from rest at
    0.02 rad/s: (top torque [kN m], bit speed [1/t*]) rows, g (rho - rho_mud) A r L sin(incl)
    of the pipe and of the BHA [kN m], the simulator, the pipe's torque on the BHA [kN m]."""
    g = replace(lossless_string(load_preset("base")),
                well=Well(SLANT, friction_static=mu_s, friction_dynamic=mu_d))
    _p, params = _rig(g)
    sim = StringSimulator(params.groups, geometry_waves(params, g, H))
    sim.start_at_rest(gap=1e9)
    sim.set_commands(0.0, 0.02 * params.scales.time_s)
    rows = sim.record(duration, 0.05)                     # [t*]: 84 s
    torque_knm = rows[:, kn.O_TS] * params.scales.stiffness_nm_per_rad / 1e3
    pipe, bha = (sum(_w(g, x) * math.sin(math.radians(30.0)) * x.length_m * x.od_m / 2 / 1e3
                     for x in g.parts() if x.bha == rigid) for rigid in (False, True))
    bottom_knm = rows[:, dk.O_T_BOTTOM] * params.scales.stiffness_nm_per_rad / 1e3
    return torque_knm, rows[:, kn.O_OMEGA], pipe, bha, sim, bottom_knm


def test_break_off_torque_of_a_slant_well_is_the_closed_form():
    """The top turned slowly from rest: the bit starts to turn when the top's torque reaches
    mu_s g (rho - rho_mud) sum A_i r_i L_i sin(incl) over the pipe and the rigid BHA, 1 %
    (measured -0.1 %, the waves' share); sliding on, the torque stays at mu_d's (0.5 %).
    Either share left out (the BHA's is a third here) misses by far more."""
    torque, omega, pipe, bha, sim, _bottom = _turned_slowly(0.3, 0.3)
    start = int(np.argmax(omega > 1e-6))
    assert start > 0
    assert torque[:start + 1].max() == pytest.approx(0.3 * (pipe + bha), rel=1e-2)
    assert torque[-200:].mean() == pytest.approx(0.3 * (pipe + bha), rel=5e-3)
    assert not sim.wall_held.any()                  # the whole pipe and the BHA slide
    assert sim.wall_friction()[0] > 0.0


def test_static_above_sliding_friction_breaks_off_from_the_top():
    """mu_s > mu_d: the stations break loose one after another from the top (those above
    already sliding), the BHA last. Until the last station breaks loose no torque reaches the
    BHA, and the top's torque peaks at mu_d's over the 7 parts above plus mu_s's of the last
    (3 %; measured -1.4 %; a station held only by mu_d: -6.7 %); the bit starts to turn when
    the top's torque is the pipe's sliding friction and the BHA's static one (3 %; measured
    +0.4 %), between the sliding and the static closed forms."""
    torque, omega, pipe, bha, _sim, bottom = _turned_slowly(0.4, 0.25)
    reached = int(np.argmax(np.abs(bottom) > 1e-3 * pipe))     # the last station broke loose
    assert reached > 0
    assert torque[:reached + 1].max() == pytest.approx((0.25 * 7 / 8 + 0.4 / 8) * pipe,
                                                       rel=3e-2)
    start = int(np.argmax(omega > 1e-6))
    assert start > reached
    peak = torque[:start + 1].max()
    assert 0.25 * (pipe + bha) < peak < 0.4 * (pipe + bha)
    assert peak == pytest.approx(0.25 * pipe + 0.4 * bha, rel=3e-2)


@pytest.mark.slow("on bottom in a build with the wall rubbing, the ledger over 200 t*: ~2.6 s")
def test_energy_balance_includes_the_walls_friction():
    """On bottom in the built well (friction 0.3 / 0.25, the preset's damping): the top
    drive's work = stored energy + bit, dashpots, transport and the wall's dissipation, and
    likewise axially (1e-5; measured 2e-7); the wall takes a share worth booking."""
    g = replace(load_preset("base").string,
                well=Well(BUILD, friction_static=0.3, friction_dynamic=0.25))
    _p, params = _rig(g)
    sim = StringSimulator(params.groups, geometry_waves(params, g, H))
    sim.start_steady(9.6, 1.32, 1e-3)
    m, rot, ax = energy_ledger(sim)
    wall = sim.wall_friction()
    assert rot == pytest.approx(m.work_top_drive, rel=1e-5)
    assert ax == pytest.approx(m.work_weight + m.work_hoist, rel=1e-5)
    assert wall[0] > 0.1 * m.work_top_drive and wall[1] > 0.0


def test_steady_start_against_the_wall_is_an_equilibrium():
    """Sliding everywhere at omega0 and v0: every station carries the wall's sliding
    friction against the resultant velocity, the bit drills under the hook's w0 less the
    axial drag; nothing moves from it in 20 t* (1e-9)."""
    g = replace(load_preset("base").string,
                well=Well(BUILD, friction_static=0.3, friction_dynamic=0.25))
    _p, params = _rig(g)
    waves = geometry_waves(params, g, H)
    sim = StringSimulator(params.groups, waves)
    sim.start_steady(9.6, 1.32, 0.0)
    bit = sim.steady_state
    assert sim.state().ts == pytest.approx(waves.steady_top_torque(bit.t0, 1.32, bit.v0),
                                           rel=1e-12)
    sim.advance(round(20.0 / H))
    s = sim.state()
    assert s.omega == pytest.approx(1.32, abs=1e-9) and s.v == pytest.approx(bit.v0, rel=1e-9)
    assert not sim.wall_held.any()


def test_friction_off_is_the_string_without_a_wall_exactly():
    """A survey with friction 0: the same wave lines and the same trajectory, to the last bit,
    as no well at all (the lumped figures the same too, W_s aside)."""
    p = load_preset("base")
    g = p.string
    rows = []
    for well in (None, Well(BUILD, friction_static=0.0, friction_dynamic=0.0)):
        waves = geometry_waves(p.rig, replace(g, well=well), H)
        assert waves.wall is None
        sim = StringSimulator(p.rig.groups, waves)
        sim.start_steady(9.6, 1.32, 1e-3)
        rows.append(sim.record(30.0, 0.1))
    assert np.array_equal(rows[0], rows[1])


@pytest.mark.parametrize("well, words", [
    ({"survey": [[0, 0, 0], [500, 10, 0]]}, "last row is at 500 m, above the bit at 1100 m"),
    ({"survey": [[10, 0, 0], [2000, 0, 0]]}, "expected the first row at measured depth 0"),
    ({"survey": [[0, 0, 0], [900, 10, 0], [800, 20, 0], [2000, 20, 0]]},
     "expected measured depths increasing"),
    ({"survey": [[0, 0, 0], [2000, 200, 0]]}, "inclination [deg] = 200.0 is out of range"),
    ({"survey": [[0, 0], [2000, 0, 0]]}, "expected [measured depth m, inclination deg"),
    ({"survey": [[0, 0, 0], [2000, 30, 0]], "friction_static": 0.2,
      "friction_dynamic": 0.3}, "friction_dynamic = 0.3 is out of range"),
    ({"survey": [[0, 0, 0], [2000, 30, 0]], "friction_static": -0.1}, "friction_static"),
    ({"survey": "north"}, "well.survey is str"),
    ({"slope": 3}, "unknown key(s) ['slope'] in 'well'"),
])
def test_bad_wells_are_refused_naming_what_is_wrong(well, words):
    name, data = read_yaml("preset", "presets", "base")
    with pytest.raises(ParameterError) as info:
        preset_from_dict(name, {**data, "well": well})
    assert words in str(info.value) and "well" in str(info.value)


def test_a_preset_well_and_a_bags_record_of_it():
    """A preset's ``well`` section reaches the string (W_s along the axis, friction at the
    stations) and a bag's record of the geometry reads it back exactly."""
    name, data = read_yaml("preset", "presets", "base")
    preset = preset_from_dict(name, {**data, "well": {
        "survey": [list(r) for r in BUILD], "friction_static": 0.3, "friction_dynamic": 0.25}})
    g = preset.string
    assert g.well == Well(BUILD, 0.3, 0.25)
    assert preset.rig.submerged_weight_n == pytest.approx(g.lumped()["submerged_weight_n"])
    assert geometry_waves(preset.rig, g, H).wall is not None
    assert geometry_from_record(geometry_record(g)) == g


def test_every_rubbing_station_obeys_coulombs_law_at_every_step():
    """field_a's start-up (the pipe's stations coupled through the material's relative
    dashpots, sticking and breaking loose): at every step, each station's wall force, read
    from the departures' balance at the junction (the arriving invariants, its impedances and
    dashpots, its neighbours' speeds: not the solver's own figure), is the sliding friction
    against the resultant sliding velocity (1e-9), or at rest within what the wall holds
    (static if it was at rest the step before, else sliding). Fails if the contacts are solved
    for the wrong coupling or stop at the wrong threshold."""
    from drill_sim.core.rig import Rig
    preset = load_preset("field_a")
    rig = Rig(preset.rig, None, top_drive=preset.top_drive, string_model="distributed",
              geometry=preset.string)
    sim = rig.sim
    t_line, a_line = sim._t, sim._a
    static, dynamic, kappa, sigma = sim._wall[:4]
    assert np.any(t_line.rel > 0.0)                  # the stations are coupled
    m = t_line.z.size
    rig.start_at_rest(0.05)
    seen_rest = seen_slide = 0
    for k in range(140):                             # 7 s of the 60 rpm start-up
        t = 0.05 * (k + 1)
        rig.command(min(t / 10.0, 1.0) * 60.0 * math.pi / 30.0, preset.rig.submerged_weight_n)
        while rig.time_s < t - 1e-12:
            held_before = sim.wall_held.copy()
            sim.advance(1)
            # scratch rows: arriving invariants a, b (torsional, axial), the stations' speeds
            sc = sim._scratch
            for j in range(1, m):
                if static[j - 1] <= 0.0:
                    continue
                forces = []
                for line, a_in, b_in, w in ((t_line, sc[0], sc[1], sc[4]),
                                            (a_line, sc[2], sc[3], sc[5])):
                    z, c, rel = line.z, line.c, line.rel
                    r = a_in[j - 1] - b_in[j] + rel[j - 1] * w[j - 1]
                    r += rel[j] * w[j + 1] if j < m - 1 else 0.0
                    d = z[j - 1] + z[j] + c[j - 1] + rel[j - 1] + rel[j]
                    forces.append(r - d * w[j])
                tangential = forces[0] * sigma / kappa[j - 1]        # [F*]
                force = math.hypot(forces[1], tangential)
                u_t, u_a = kappa[j - 1] * sc[4][j], sc[5][j]
                speed = math.hypot(u_t, u_a)
                if speed == 0.0:
                    seen_rest += 1
                    cap = static[j - 1] if held_before[j - 1] else dynamic[j - 1]
                    assert force <= cap * (1.0 + 1e-9)
                else:
                    seen_slide += 1
                    assert tangential == pytest.approx(dynamic[j - 1] * u_t / speed,
                                                       abs=1e-9 * dynamic[j - 1])
                    assert forces[1] == pytest.approx(dynamic[j - 1] * u_a / speed,
                                                      abs=1e-9 * dynamic[j - 1])
    assert seen_rest > 1000 and seen_slide > 1000


def test_the_rubbing_bha_obeys_coulombs_law_at_every_step():
    """field_a's 60 rpm start-up off bottom (the bit's laws silent, w = t = 0): at every step
    the wall's torque and force on the rigid BHA, read from the BHA's own momentum balance
    over the step (the pipe's torque and force on it less the change of its speeds: not the
    solver's figure), are the sliding friction against the resultant sliding velocity
    (v, r omega) (1e-9), or at rest within what the wall holds (static if it was at rest the
    step before, else sliding); the BHA rests, breaks loose, and rests again. Fails if the
    BHA does not rub, rubs at the wrong radius or threshold, or its contact is solved apart
    from the bit's laws' step."""
    from drill_sim.core.rig import Rig
    preset = load_preset("field_a")
    rig = Rig(preset.rig, None, top_drive=preset.top_drive, string_model="distributed",
              geometry=preset.string)
    sim = rig.sim
    static, dynamic, kappa = (float(a[-1]) for a in sim._wall[:3])
    sigma = sim._wall[3]
    assert static > 0.0 and dynamic > 0.0
    h, psi = sim.dt, sim._p[kn.P_PSI]
    rig.start_at_rest(0.05)
    rests = slides = rests_after_sliding = 0
    for k in range(280):                             # 14 s: loose at about 11 s
        t = 0.05 * (k + 1)
        rig.command(min(t / 10.0, 1.0) * 60.0 * math.pi / 30.0, preset.rig.submerged_weight_n)
        while rig.time_s < t - 1e-12:
            x = sim._x
            om, v, held_before = x[kn.X_OMEGA], x[kn.X_V], sim.wall_held[-1]
            sim.advance(1)
            assert x[kn.X_DELTA] < 0.0                  # off bottom: the bit takes nothing
            om_new, v_new = x[kn.X_OMEGA], x[kn.X_V]
            torque = x[dk.X_T_BOTTOM] - (om_new - om) / h
            axial = x[dk.X_F_BOTTOM] - (v_new - v) / (h * psi)
            tangential = torque * sigma / kappa             # [F*]
            u_t, u_a = kappa * om_new, v_new
            speed = math.hypot(u_t, u_a)
            if speed == 0.0:
                rests += 1
                rests_after_sliding += slides > 0
                cap = static if held_before else dynamic
                assert math.hypot(tangential, axial) <= cap * (1.0 + 1e-9)
            else:
                slides += 1
                assert tangential == pytest.approx(dynamic * u_t / speed, abs=1e-9 * dynamic)
                assert axial == pytest.approx(dynamic * u_a / speed, abs=1e-9 * dynamic)
    assert rests > 1000 and slides > 1000 and rests_after_sliding > 100


def test_the_bhas_contact_is_its_sections_wall_force_at_their_radii():
    """field_a's BHA lies in the straight 60 deg hole: the wall presses each section by its
    buoyed weight per metre times sin 60 deg (no bend, no tension term), so the BHA's contact
    carries sum w_i L_i sin 60 deg and rubs at the radius those forces weight (its break-off
    torque mu_s sum w_i L_i r_i sin 60 deg), 1e-9."""
    from drill_sim.core.distributed import bha_contact
    g = load_preset("field_a").string
    parts = [x for x in g.parts() if x.bha]
    assert len(parts) == 6
    force = sum(_w(g, x) * x.length_m for x in parts) * math.sin(math.radians(60.0))
    moment = sum(_w(g, x) * x.length_m * x.od_m / 2 for x in parts) * math.sin(math.radians(60))
    contact = bha_contact(g)
    assert contact.normal_force_n == pytest.approx(force, rel=1e-9)
    assert contact.radius_m * contact.normal_force_n == pytest.approx(moment, rel=1e-9)
    assert (contact.friction_static, contact.friction_dynamic) == (0.885, 0.425)
    assert bha_contact(load_preset("base").string) is None          # vertical: none
