"""The field preset ``field_a`` (Aarsnes & Shor's Well A) against figures computed here from the
published geometry alone: its first torsional mode (the shaft with the BHA's inertia at the
bottom, ≈ 0.22 Hz as they report), W_s along the hole's axis over the survey; and its off-bottom
start-up: the string winds up, breaks loose, and at 60 rpm keeps sticking (static friction
above sliding friction: off-bottom stick-slip), where with static = sliding friction it settles."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from drill_sim.control.tuning import first_mode_frequency_hz
from drill_sim.core.presets import load_preset
from drill_sim.core.rig import Rig

RPM = 2.0 * math.pi / 60.0
G_PIPE, RHO, RHO_MUD, GRAVITY = 61e9, 7850.0, 1200.0, 9.80665     # standard gravity
PIPE = (2269.54, 0.1465, 0.1230)
BHA = ((19.08, 0.1502, 0.0968), (10.24, 0.2064, 0.0762), (57.24, 0.1502, 0.0968),
       (9.75, 0.2062, 0.0699), (95.40, 0.1502, 0.0968), (38.75, 0.2224, 0.0960))


def _polar(od: float, inner: float) -> float:
    return math.pi / 32.0 * (od**4 - inner**4)


def _area(od: float, inner: float) -> float:
    return math.pi / 4.0 * (od**2 - inner**2)


@pytest.fixture(scope="module")
def field_a():
    return load_preset("field_a")


def test_the_first_mode_is_the_shafts_with_the_bhas_inertia(field_a):
    """Top held (the drive's stiff PI), the rigid BHA's inertia at the bottom: θ tan θ = 1/μ,
    μ = I_BHA / (ρ J_p L), f = θ c / (2π L); 0.226 Hz, where Aarsnes & Shor give ≈ 0.22 Hz."""
    length, od, inner = PIPE
    shaft = RHO * _polar(od, inner) * length
    bha = sum(RHO * _polar(o, i) * n for n, o, i in BHA)
    mu = bha / shaft
    lo, hi = 1e-6, math.pi / 2 - 1e-9
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if mid * math.tan(mid) < 1.0 / mu else (lo, mid)
    exact = 0.5 * (lo + hi) * math.sqrt(G_PIPE / RHO) / (2 * math.pi * length)
    f1 = first_mode_frequency_hz(field_a, None, string_model="distributed")
    assert f1 == pytest.approx(exact, rel=1e-3)
    assert f1 == pytest.approx(0.22, rel=0.05)
    assert field_a.rig.bha_inertia_kg_m2 == pytest.approx(bha, rel=1e-9)


def test_the_weight_along_the_hole_is_summed_over_the_survey(field_a):
    """Vertical to 1500 m, inclination rising linearly with depth to 60° at 2100 m (a circular
    arc: ∫cos θ ds = 600 m · sin 60° / (π/3)), 60° below: the pipe's buoyed weight per metre
    times its length along the vertical, the BHA's at cos 60°."""
    buoyancy = 1.0 - RHO_MUD / RHO
    length, od, inner = PIPE
    w_pipe = RHO * _area(od, inner) * GRAVITY * buoyancy
    arc = 600.0 * math.sin(math.pi / 3) / (math.pi / 3)
    pipe_vertical = 1500.0 + arc + (length - 2100.0) * 0.5
    bha = sum(RHO * _area(o, i) * n for n, o, i in BHA) * GRAVITY * buoyancy * 0.5
    assert field_a.rig.submerged_weight_n == pytest.approx(w_pipe * pipe_vertical + bha,
                                                           rel=1e-6)


def _start_up(preset, rpm: float, duration_s: float) -> dict[str, np.ndarray]:
    """The scenario ``startup_off_bottom`` on the rig: at rest 5 cm off bottom, the hook
    holding the whole string, the speed set-point ramped from 0 to ``rpm`` in 10 s."""
    rig = Rig(preset.rig, 1e-4, top_drive=preset.top_drive, string_model="distributed",
              geometry=preset.string)
    rig.start_at_rest(0.05)
    t, bit, top, torque = [], [], [], []
    for k in range(1, round(duration_s / 0.01) + 1):
        rig.command(min(k * 0.01 / 10.0, 1.0) * rpm * RPM, preset.rig.submerged_weight_n)
        rig.advance_to(k * 0.01)
        s = rig.sample()
        t.append(s.time_s)
        bit.append(s.bit_speed_rad_s)
        top.append(s.top_drive_speed_rad_s)
        torque.append(s.surface_torque_nm)
    return {"t": np.array(t), "bit": np.array(bit), "top": np.array(top),
            "torque": np.array(torque)}


@pytest.mark.slow(reason="two 45 s runs of the 2500 m string rubbing along the hole, ~6 s")
def test_off_bottom_start_up_sticks_on_where_static_friction_exceeds_sliding(field_a):
    """The string stays put while the top winds it up (the bit turns only once the top has
    turned more than a revolution), then breaks loose. With their friction (static 0.885,
    sliding 0.425) the torque released at break-off swings the bit back to rest and it sticks
    again and again at 60 rpm (off-bottom stick-slip: the BHA's share alone drops by 8.6 kN m,
    a swing of ~21 rad/s about the top's speed on the first mode). With static = sliding
    (0.425) the same start-up settles: the bit never sticks again and ends at the top's
    speed (10 %)."""
    rubbing = _start_up(field_a, 60.0, 45.0)
    loose = np.argmax(rubbing["bit"] > 1e-3)
    top_turned = np.sum(rubbing["top"][:loose]) * 0.01
    assert top_turned > 2 * math.pi
    stuck = rubbing["bit"] <= 1e-6
    late = rubbing["t"] > 25.0
    assert np.sum(np.diff(stuck[late].astype(int)) == 1) >= 3       # sticks again, 3+ times
    well = replace(field_a.string.well, friction_static=0.425)
    even = _start_up(replace(field_a, string=replace(field_a.string, well=well)), 60.0, 45.0)
    loose = np.argmax(even["bit"] > 1e-3)
    assert (even["bit"][loose:] > 1e-6).all()
    late = even["t"] > 35.0
    assert np.abs(even["bit"][late] - 60 * RPM).max() < 0.1 * 60 * RPM
