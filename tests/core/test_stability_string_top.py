"""The distributed string's on-bottom roots with a top boundary (a law on the drive's inertia)
instead of the top held: a very stiff top gives the held top's roots, and a non-reflecting top
on base's uniform pipe made lossless (K = its impedance z s) gives the roots of the closed form
in which the pipe below the bit's BHA is the dashpot z s itself, derived here independently of
the transfer-matrix algebra:

    (s^2 + psi K_a + n psi E)(s^2 + z s) - k E (s^2 + psi K_a) = 0,  K_a = -a21/a11.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from drill_sim.cli.case import si_case
from drill_sim.core import load_preset
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.stability import steady_state
from drill_sim.core.stability_distributed import string_stability


@pytest.fixture(scope="module")
def base_string():
    preset = load_preset("base")
    case = si_case(preset, 60.0, 100.0)
    waves = geometry_waves(preset.rig, preset.string, 5e-4, continuous=True)
    assert waves.torsion.z.size == 1 and not waves.torsion.dashpot.any()   # one uniform tube
    return case, waves


def test_a_very_stiff_top_gives_the_held_tops_roots(base_string):
    case, waves = base_string
    held = string_stability(case.groups, waves, case.w0, case.omega0)
    stiff = string_stability(case.groups, waves, case.w0, case.omega0,
                             top=lambda s: (1e9 * np.ones_like(s), np.ones_like(s)))
    assert held.complete and stiff.complete and stiff.roots.size == held.roots.size
    assert held.roots_at_zero == stiff.roots_at_zero == 1
    assert np.allclose(stiff.roots, held.roots, atol=1e-6)


def test_a_non_reflecting_top_gives_the_roots_of_the_pipe_as_its_impedance(base_string):
    """Every root found with K = z s zeroes the closed form (relative to its terms), and the
    rightmost differs from the held top's: the top boundary reaches the characteristic."""
    case, damped = base_string
    g = case.groups
    zeros = np.zeros(1)
    waves = dataclasses.replace(damped, torsion=dataclasses.replace(damped.torsion, eta=zeros,
                                                                    nu=zeros))
    z = float(waves.torsion.z[0])

    def w(s):
        return z * np.asarray(s, dtype=complex)
    res = string_stability(g, waves, case.w0, case.omega0,
                           top=lambda s: (w(s), np.ones_like(np.asarray(s, dtype=complex))))
    # the string turns and rises freely as a whole (no static stiffness at the top): s = 0 twice
    assert res.complete and res.roots_at_zero == 2 and res.roots.size > 0
    st = steady_state(g, case.w0, case.omega0)
    k = g.n * (st.w0 - g.lam) / (2.0 * math.pi)
    s = res.roots
    e = 1.0 - np.exp(-s * st.tau_n0)
    a11, _, a21, _ = waves.axial.transfer(s)
    ka = -a21 / a11
    s2 = s * s
    first = (s2 + g.psi * ka + g.n * g.psi * e) * (s2 + w(s))
    second = k * e * (s2 + g.psi * ka)
    assert np.all(np.abs(first - second) <= 1e-7 * (np.abs(first) + np.abs(second)))
    held = string_stability(g, waves, case.w0, case.omega0)
    assert not np.allclose(res.roots[:2], held.roots[:2], atol=1e-3)
