"""Maps against the seed's claims and the linear theory: no stick for 1 < beta <= 2 where
contact is kept (omega0 1.6 to 4, w0 8 to 12; slower, heavier or with beta = 3 the bit sticks
with contact kept too, see msg_docs/map.md), the stick region's trends with speed and weight on
the base rig, the axial neutral line against the roots of Delta(s), and the specific energy of
steady drilling."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from drill_sim.cli.main import main
from drill_sim.core import Metrics, load_preset, steady_state
from drill_sim.core.stability import stability
from drill_sim.study import axial_neutral_speed, axial_threshold, metric_row

GROUPS = "n=4,psi=13.73,lambda=6.84,beta={beta}"


def table(path) -> list[dict[str, float]]:
    with open(path, newline="") as fh:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(fh)]


def spearman(a, b) -> float:
    ra, rb = np.argsort(np.argsort(a)), np.argsort(np.argsort(b))
    return float(np.corrcoef(ra, rb)[0, 1])


@pytest.mark.parametrize("beta, sticks", [(1.2, False), (1.5, False), (2.0, False),
                                          (0.36, True)])
def test_no_stick_above_beta_one_where_contact_is_kept(tmp_path, beta, sticks):
    out = tmp_path / "b.csv"
    assert main(["map", "--groups", GROUPS.format(beta=beta), "--omega0", "1.6,2.5,4",
                 "--w0", "8,9.6,12", "--duration", "400", "--workers", "1",
                 "--out", str(out)]) == 0
    points = table(out)
    assert all(p["bounce_fraction"] == 0 for p in points)          # contact regimes only
    if sticks:
        assert sum(p["stick_fraction"] > 0.05 for p in points) >= 3
    else:
        assert all(p["stick_fraction"] == 0 for p in points)
        assert all(p["ssi"] < 1 for p in points)


def test_stick_region_shrinks_with_speed_and_grows_with_weight(tmp_path):
    out = tmp_path / "t.csv"
    rpm, wob = [30, 60, 120, 250], [80, 120, 200, 300]
    assert main(["map", "--rpm", ",".join(map(str, rpm)), "--wob-kn", ",".join(map(str, wob)),
                 "--duration", "40", "--out", str(out)]) == 0
    stick = np.array([p["stick_fraction"] for p in table(out)]).reshape(len(rpm), len(wob))
    # ends of the range: slow sticks more than fast at every weight; heavy more than light
    assert np.all(stick[0] > 0.02) and np.all(stick[-1] == 0)
    assert np.all(stick[:-1, -1] > stick[:-1, 0])
    # along the edges and across: falls with speed, rises with weight (above the friction
    # weight 71 kN, where there is no trend, from the second weight on)
    for j in range(1, len(wob)):
        assert spearman(rpm, stick[:, j]) <= -0.8, wob[j]
    for i in range(len(rpm) - 1):
        assert spearman(wob, stick[i]) >= 0.6, rpm[i]


@pytest.mark.parametrize("w0", [7.5, 9.6, 15.0, 25.0])
def test_axial_neutral_line_is_where_the_roots_of_delta_cross(w0):
    g = load_preset("base").rig.groups
    speed = float(axial_neutral_speed(g.n, g.psi, g.lam, w0))

    def axial_growth(omega0: float) -> float:
        roots = stability(g, w0, omega0, re_min=-0.2).roots
        return max((r.real for r in roots if abs(r.imag) > 3.0), default=-math.inf)

    assert axial_growth(0.98 * speed) > 0.05 and axial_growth(1.02 * speed) < -0.05
    assert speed < float(axial_threshold(g.n, g.psi))
    assert float(axial_neutral_speed(g.n, g.psi, g.lam, g.lam * (1 + 1e-12))) == pytest.approx(
        float(axial_threshold(g.n, g.psi)), rel=1e-9)
    assert math.isnan(float(axial_neutral_speed(g.n, g.psi, g.lam, g.lam)))


def test_specific_energy_of_steady_drilling():
    """MSE = W/A + Omega0 T/(A ROP); steady drilling's rotary term is eps (1 + beta lambda /
    (w0 - lambda)), Detournay's specific energy with friction."""
    rig = load_preset("base").rig
    g, sc = rig.groups, rig.scales
    w0, omega0 = 9.6, 1.32
    st = steady_state(g, w0, omega0)
    m = Metrics(1.0, 0.0, 0.0, 0.0, omega0, omega0, omega0, w0, st.t0, st.t0, st.v0, w0, omega0,
                *[0.0] * 5)
    rotary = metric_row(m, omega0, None)["mse_rotary"]
    assert rotary == pytest.approx(1 + g.beta * g.lam / (w0 - g.lam), rel=1e-12)
    si = metric_row(m, omega0, rig)
    area = math.pi * rig.bit_radius_m ** 2
    by_hand = (w0 * sc.force_n / area + (omega0 / sc.time_s) * st.t0 * sc.stiffness_nm_per_rad
               / (area * st.v0 * sc.velocity_m_s))
    assert si["mse_pa"] == pytest.approx(by_hand, rel=1e-12)
    assert si["speed_drop"] == 0.0 and si["mean_rop_m_s"] == pytest.approx(st.v0 * sc.velocity_m_s)
    stopped = Metrics(1.0, math.inf, 1.0, 0.0, 0.0, 0.0, 0.0, w0, 1.0, 1.0, 0.0, w0, omega0,
                      *[0.0] * 5)
    row = metric_row(stopped, omega0, rig)
    assert row["speed_drop"] == 1.0 and math.isnan(row["mse_pa"])
