"""The uniform pipe's theory in SI, computed from a preset's geometry alone, so the distributed
string's tests compare the simulation with physics and not with the code's own wave lines
(a wrong density or damping in the code's SI conversion then shows).

A pipe of length L, mass (or inertia) per length m, stiffness K (G J or E A) and viscous damping
c per length: m x_tt + c x_t = K x_xx, so in Laplace s the wave number is
k = sqrt(s (s + c/m)) / v, v = sqrt(K/m), and the impedance is sqrt(K m) (lossless).
Torsion: the top held, the BHA's inertia I at the bottom: I s^2 sinh(kL) + K k cosh(kL) = 0.
Axial: the hook force held (a free top), the BHA's mass M at the bottom:
M s^2 cosh(kL) + K k sinh(kL) = 0."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

YOUNG_MODULUS_PA = 200e9


@dataclass(frozen=True)
class Pipe:
    """One uniform pipe: per length m [kg/m or kg m], stiffness K [N or N m^2], damping c per
    length, length [m], and the BHA's end inertia or mass."""

    m: float
    k: float
    c: float
    length_m: float
    end: float

    @property
    def speed_m_s(self) -> float:
        return math.sqrt(self.k / self.m)

    @property
    def impedance(self) -> float:
        """sqrt(K m): N m s/rad (torsion) or N s/m (axial)."""
        return math.sqrt(self.k * self.m)


def polar_moment_m4(od_m: float, id_m: float) -> float:
    return math.pi / 32.0 * (od_m ** 4 - id_m ** 4)


def area_m2(od_m: float, id_m: float) -> float:
    return math.pi / 4.0 * (od_m ** 2 - id_m ** 2)


def pipe(kind: str, preset, geometry=None, young_modulus_pa: float = YOUNG_MODULUS_PA) -> Pipe:
    """The preset's pipe (``geometry``: another one, e.g. with damping) as torsion or axial."""
    g = geometry if geometry is not None else preset.string
    rho = g.steel_density_kg_m3
    if kind == "torsion":
        j = polar_moment_m4(g.pipe_od_m, g.pipe_id_m)
        return Pipe(rho * j, g.shear_modulus_pa * j, g.torsional_damping_nm_s_per_rad_m,
                    g.pipe_length_m, preset.rig.bha_inertia_kg_m2)
    a = area_m2(g.pipe_od_m, g.pipe_id_m)
    return Pipe(rho * a, young_modulus_pa * a, g.axial_damping_n_s_per_m2, g.pipe_length_m,
                preset.rig.bha_mass_kg)


def _lossless(kind: str, p: Pipe, w: float) -> float:
    theta = w * p.length_m / p.speed_m_s
    if kind == "torsion":
        return -p.end * w * math.sin(theta) + p.k / p.speed_m_s * math.cos(theta)
    return p.end * w * math.cos(theta) + p.k / p.speed_m_s * math.sin(theta)


def natural_frequencies_rad_s(kind: str, p: Pipe, count: int) -> list[float]:
    """The first ``count`` angular frequencies of the lossless pipe [rad/s]: sign changes of
    the real frequency equation on s = i w, refined by bisection."""
    top = (count + 1) * math.pi * p.speed_m_s / p.length_m
    ws = np.linspace(1e-6, top, 400_001)
    values = np.array([_lossless(kind, p, w) for w in ws])
    out = []
    for i in np.nonzero(np.sign(values[1:]) != np.sign(values[:-1]))[0][:count]:
        low, high, sign = ws[i], ws[i + 1], np.sign(values[i])
        for _ in range(60):
            mid = 0.5 * (low + high)
            low, high = (mid, high) if np.sign(_lossless(kind, p, mid)) == sign else (low, mid)
        out.append(0.5 * (low + high))
    return out


def first_root(kind: str, p: Pipe) -> complex:
    """The first mode's root s [1/s] with the damping: Newton from the lossless one."""
    def f(s):
        k = np.sqrt(s * (s + p.c / p.m)) / p.speed_m_s
        if kind == "torsion":
            return p.end * s * s * np.sinh(k * p.length_m) + p.k * k * np.cosh(k * p.length_m)
        return p.end * s * s * np.cosh(k * p.length_m) + p.k * k * np.sinh(k * p.length_m)
    s = 1j * natural_frequencies_rad_s(kind, p, 1)[0]
    for _ in range(80):
        d = 1e-7 * abs(s)
        s = s - f(s) / ((f(s + d) - f(s - d)) / (2 * d))
    return complex(s)


def natural_frequencies_with_top_inertia_rad_s(p: Pipe, top_inertia: float, count: int
                                               ) -> list[float]:
    """The first ``count`` torsional angular frequencies [rad/s] of the lossless pipe with an
    inertia J at its top (a top drive under a constant motor torque) and the BHA's I at its
    bottom, the rigid turning excluded. With theta = w L/v and a = J w v/K:
    I w (cos theta - a sin theta) + (K/v)(sin theta + a cos theta) = 0."""
    def g(w: float) -> float:
        theta, a = w * p.length_m / p.speed_m_s, top_inertia * w * p.speed_m_s / p.k
        return (p.end * w * (math.cos(theta) - a * math.sin(theta))
                + p.k / p.speed_m_s * (math.sin(theta) + a * math.cos(theta)))
    top = (count + 1) * math.pi * p.speed_m_s / p.length_m
    ws = np.linspace(1e-6, top, 400_001)
    values = np.array([g(w) for w in ws])
    out = []
    for i in np.nonzero(np.sign(values[1:]) != np.sign(values[:-1]))[0][:count]:
        low, high, sign = ws[i], ws[i + 1], np.sign(values[i])
        for _ in range(60):
            mid = 0.5 * (low + high)
            low, high = (mid, high) if np.sign(g(mid)) == sign else (low, mid)
        out.append(0.5 * (low + high))
    return out
