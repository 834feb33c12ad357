"""Z-Torque's saturation regulator (msg_docs/control.md, "The saturation regulator"): the α in
use falls at backoff (1 - s) per second while the output is on a limit, climbs back at
backoff s otherwise, between alpha_min and α; off by default, and where it is off or the motor
never touches a limit the law is the plain one, output for output."""

from __future__ import annotations

import math

import pytest

from drill_sim.control import SurfaceMeasurement, make_law

H, Z, J = 1e-3, 302.4, 2900.0
LIMIT_NM = 1000.0


def _law(limit_nm: float = LIMIT_NM, **gains):
    """α 0.4, no integral (the output is K_p e, on or off a limit at once)."""
    law = make_law("z_torque", H, Z, J, alpha=0.4, ki_nm_rad=0.0, torque_min_nm=-limit_nm,
                   torque_max_nm=limit_nm, **gains)
    law.reset(10.0)
    return law


def test_alpha_backs_off_on_a_limit_and_climbs_back_off_it_at_the_documented_rates():
    """Held on the upper limit (the speed 10 rad/s below the set-point) for n samples the
    scale is 1 - n h b (1 - s), worked by hand, down to alpha_min / α; then off the limit
    (the set-point brought to the speed, the output 0) it climbs by h b s a sample."""
    b, s = 2.0, 0.1
    law = _law(backoff_per_s=b, saturation_target=s, alpha_min=0.1)
    below = SurfaceMeasurement(0.0, 0.0, 0.0, 0.0)
    outputs = [law.step(below) for _ in range(100)]
    assert outputs == [LIMIT_NM] * 100
    assert law.alpha_in_use == pytest.approx(0.4 * (1.0 - 100 * H * b * (1.0 - s)), rel=1e-9)
    for _ in range(1000):                       # 1.8 of the scale asked: the floor holds
        law.step(below)
    assert law.alpha_in_use == pytest.approx(0.1, rel=1e-12)
    law.set_speed(0.0)
    above = below
    outputs = [law.step(above) for _ in range(500)]
    assert outputs == [0.0] * 500
    assert law.alpha_in_use == pytest.approx(0.1 + 0.4 * 500 * H * b * s, rel=1e-9)
    for _ in range(10_000):                     # 2 of the scale asked: α is the ceiling
        law.step(above)
    assert law.alpha_in_use == pytest.approx(0.4, rel=1e-12)
    law.reset(10.0)
    law.step(below)
    assert law.alpha_in_use == pytest.approx(0.4 * (1.0 - H * b * (1.0 - s)), rel=1e-12)


def test_a_law_without_the_regulator_or_off_its_limits_is_the_plain_law():
    """Off by default; on, but never on a limit, every output is the plain law's, to the bit."""
    plain, regulated, default = _law(1e5), _law(1e5, backoff_per_s=5.0), _law()
    assert default.backoff_per_s == 0.0 and default.alpha_in_use == 0.4
    for law in (plain, regulated):               # turning steadily at the set-point
        law.bumpless_start(0.0, SurfaceMeasurement(0.0, 10.0, 0.0, 0.0))
    inputs = [SurfaceMeasurement(k * H, 10.0 + 0.01 * math.sin(0.05 * k),
                                 200.0 * math.cos(0.05 * k), 0.0) for k in range(3000)]
    got = [(plain.step(m), regulated.step(m)) for m in inputs]
    assert 1e3 < max(abs(out) for out, _ in got) < 1e5
    assert [a for a, _ in got] == [b for _, b in got]
    assert regulated.alpha_in_use == 0.4


def test_taking_over_restores_the_full_alpha():
    """A bumpless start (the law taking over) starts again from α, whatever it backed off to."""
    law = _law(backoff_per_s=2.0)
    for _ in range(200):
        law.step(SurfaceMeasurement(0.0, 0.0, 0.0, 0.0))
    assert law.alpha_in_use < 0.4
    law.bumpless_start(500.0, SurfaceMeasurement(0.0, 10.0, 500.0, 500.0))
    assert law.alpha_in_use == 0.4


def test_a_floor_at_or_above_alpha_never_backs_off():
    """alpha_min at or above α (α lowered below the reference's 0.15 floor): on a limit the
    law keeps α, and α can be lowered without touching the floor."""
    law = _law(backoff_per_s=2.0, alpha_min=0.5)
    for _ in range(200):
        assert law.step(SurfaceMeasurement(0.0, 0.0, 0.0, 0.0)) == LIMIT_NM
    assert law.alpha_in_use == 0.4
