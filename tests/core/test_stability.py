"""Steady drilling (model contract, section 4) and the roots of Delta(s) (section 5)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drill_sim.core import Groups, NoSteadyDrilling, Simulator, steady_state
from drill_sim.core.stability import characteristic, stability


def test_steady_state_in_si_matches_model_md(base, base_commands):
    rig, sc = base.rig, base.rig.scales
    st = steady_state(rig.groups, *base_commands)
    w0_n = 1e5
    a, eps, zeta = rig.bit_radius_m, rig.intrinsic_specific_energy_pa, rig.cutting_inclination
    d0 = (w0_n - rig.friction_weight_n) / (a * zeta * eps)                 # per revolution
    omega0 = base.top_drive_speed_rad_s
    t0 = a * a * eps / 2 * d0 + a / 2 * rig.friction_coefficient * rig.wear_flat_orientation \
        * rig.friction_weight_n
    assert st.delta_n0 * rig.blade_count * sc.length_m == pytest.approx(d0, rel=1e-12)
    assert st.v0 * sc.velocity_m_s == pytest.approx(omega0 * d0 / (2 * math.pi), rel=1e-12)
    assert st.t0 * sc.stiffness_nm_per_rad == pytest.approx(t0, rel=1e-12)


def test_no_steady_drilling_below_friction_weight_is_said_clearly(base_groups):
    with pytest.raises(NoSteadyDrilling, match="no steady drilling solution"):
        steady_state(base_groups, base_groups.lam * 0.9, 1.0)


def test_below_friction_weight_the_bit_rotates_on_its_wear_flats(base_groups):
    """w0 <= lambda is a valid simulation: V = 0, W = w0, Omega -> omega0, T_s -> beta w0."""
    w0 = 0.8 * base_groups.lam
    sim = Simulator(base_groups)
    sim.start_at_rest()
    sim.set_commands(w0, 1.0)
    sim.run(200.0)
    sim.reset_window()
    m = sim.run(400.0).metrics
    s = sim.state()
    assert s.v == 0.0 and s.u == 0.0
    assert m.mean_wob == pytest.approx(w0, rel=1e-9)
    assert m.mean_bit_speed == pytest.approx(1.0, rel=0.01)
    assert m.mean_rop == 0.0


POINTS = [(Groups(4, 13.73, 6.84, 0.36), 9.6, 1.32), (Groups(4, 13.73, 6.84, 0.36), 8.5, 1.0),
          (Groups(3, 5.0, 3.0, 0.5), 5.0, 1.5), (Groups(4, 13.73, 6.84, 0.36), 12.0, 4.0),
          (Groups(6, 40.0, 2.0, 0.8), 4.0, 0.5)]


@pytest.mark.parametrize("groups, w0, omega0", POINTS)
def test_every_root_in_the_box_is_found_and_is_a_root(groups, w0, omega0):
    res = stability(groups, w0, omega0)
    assert res.complete, "Newton's roots must match the argument-principle count"
    assert res.count_argument_principle == res.roots.size + 1       # + the root s = 0
    value, _ = characteristic(res.roots, groups, res.steady)
    assert np.all(np.abs(value) < 1e-8 * (1 + np.abs(res.roots) ** 4))
    assert np.all(res.roots.real >= res.re_min) and np.all(np.abs(res.roots) <= res.radius)
    # conjugate pairs
    assert all(np.min(np.abs(res.roots - r.conjugate())) < 1e-8 * (1 + abs(r)) for r in res.roots)


@pytest.mark.parametrize("groups, w0, omega0", POINTS)
def test_steady_drilling_is_unstable_with_a_weak_torsional_root_near_i(groups, w0, omega0):
    """RGD: steady drilling is always unstable, with a weakly unstable root near s = +-i."""
    res = stability(groups, w0, omega0)
    assert not res.stable
    torsional = res.roots[np.argmin(np.abs(res.roots - 1j))]
    assert abs(torsional - 1j) < 0.1
    assert 0 < torsional.real < 0.05


def test_torsional_root_tends_to_i_as_the_chip_coupling_vanishes():
    """k = n (w0 - lambda)/(2 pi) -> 0 decouples: Delta -> (s^2 + 1)(s^2 + n psi E), roots +-i."""
    g = Groups(4, 13.73, 6.84, 0.36)
    res = stability(g, g.lam + 1e-6, 1.32)
    assert np.min(np.abs(res.roots - 1j)) < 1e-5


# ---- a second, independent method ------------------------------------------------------------
# Delta written out again from the model contract (section 5), and roots located by contour
# integrals (Delves-Lyness): on a circle C holding exactly one root r,
#     (1/2 pi i) oint_C Delta'/Delta ds = 1    and    (1/2 pi i) oint_C s Delta'/Delta ds = r,
# computed with the trapezoidal rule in the angle (exponentially accurate for a periodic analytic
# integrand) and Delta' by central differences. Neither Newton's method nor the code's Delta is
# used, so a wrong root, a wrong Delta or a missed root would show.

def _delta(s, groups: Groups, w0: float, omega0: float):
    n, psi, lam = groups.n, groups.psi, groups.lam
    e = 1.0 - np.exp(-s * 2.0 * math.pi / (n * omega0))
    return (s * s + 1.0) * (s * s + n * psi * e) - n * (w0 - lam) / (2.0 * math.pi) * s * s * e


def _contour_moments(center: complex, radius: float, f) -> tuple[complex, complex]:
    theta = np.linspace(0.0, 2.0 * math.pi, 4096, endpoint=False)
    ds = 1j * radius * np.exp(1j * theta)                  # ds/dtheta
    s = center + radius * np.exp(1j * theta)
    eps = 1e-6 * (1.0 + abs(center))
    log_derivative = (f(s + eps) - f(s - eps)) / (2.0 * eps) / f(s)
    weights = log_derivative * ds / (2j * math.pi) * (2.0 * math.pi / theta.size)
    return np.sum(weights), np.sum(weights * s)


def _zeros_in_box(x0: float, x1: float, y: float, f, points: int = 200_000) -> int:
    """Zeros of f in [x0, x1] x [-y, y] by the change of arg f along the edge."""
    corners = [complex(x0, -y), complex(x1, -y), complex(x1, y), complex(x0, y), complex(x0, -y)]
    path = np.concatenate([np.linspace(corners[i], corners[i + 1], points, endpoint=False)
                           for i in range(4)] + [np.array([corners[0]])])
    turns = np.diff(np.unwrap(np.angle(f(path))))
    assert np.max(np.abs(turns)) < 0.5                       # sampled finely enough
    return round(np.sum(turns) / (2.0 * math.pi))


@pytest.mark.parametrize("groups, w0, omega0", POINTS)
def test_rightmost_root_by_an_independent_method(groups, w0, omega0):
    """The rightmost root from contour moments, and no root right of it: for Re s >= x >= 0,
    |E| <= 1 + e^{-x tau} <= 2, so Delta = 0 needs |s|^4 <= |s|^2 (1 + 2 (n psi + |k|)) + 2 n psi
    (every other term bounded by the triangle inequality): all such roots have |s| <= R with
    R^2 = (A + sqrt(A^2 + 8 n psi))/2, A = 1 + 2 (n psi + |k|)."""
    res = stability(groups, w0, omega0)
    r = res.rightmost

    def f(s):
        return _delta(s, groups, w0, omega0)

    count, location = _contour_moments(r, 0.05, f)
    assert abs(count - 1.0) < 1e-8
    assert abs(location - r) < 1e-8 * (1 + abs(r))
    k = groups.n * (w0 - groups.lam) / (2 * math.pi)
    a = 1 + 2 * (groups.n * groups.psi + abs(k))
    big = 1.01 * math.sqrt((a + math.sqrt(a * a + 8 * groups.n * groups.psi)) / 2)
    # nothing right of the rightmost root (its conjugate pair lies on the edge's left)
    assert _zeros_in_box(r.real + 1e-3, big, big, f) == 0
    # and the unstable roots it lists (Re s > 0) are all there is
    assert _zeros_in_box(1e-3, big, big, f) == np.count_nonzero(res.roots.real > 1e-3)
