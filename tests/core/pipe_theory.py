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
    length, length [m], the BHA's end inertia or mass, and the material's Kelvin-Voigt
    retardation time eta [s] (stress K (strain + eta strain rate))."""

    m: float
    k: float
    c: float
    length_m: float
    end: float
    eta: float = 0.0

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
    rho, shear = g.steel_density_kg_m3, g.shear_modulus_pa
    od, inner, length = g.pipe_od_m, g.pipe_id_m, g.pipe_length_m
    if g.sections:                      # one section of pipe over the BHA's (field_a)
        [top] = [x for x in g.sections if not x.bha]
        od, inner, length = top.od_m, top.id_m, top.length_m
        rho = top.steel_density_kg_m3 or rho
        shear = top.shear_modulus_pa or shear
        young_modulus_pa = top.young_modulus_pa or young_modulus_pa
    if kind == "torsion":
        j = polar_moment_m4(od, inner)
        return Pipe(rho * j, shear * j, g.torsional_damping_nm_s_per_rad_m, length,
                    preset.rig.bha_inertia_kg_m2, g.torsional_retardation_time_s)
    a = area_m2(od, inner)
    return Pipe(rho * a, young_modulus_pa * a, g.axial_damping_n_s_per_m2, length,
                preset.rig.bha_mass_kg, g.axial_retardation_time_s)


def _lossless(kind: str, p: Pipe, w):
    theta = w * p.length_m / p.speed_m_s
    if kind == "torsion":
        return -p.end * w * np.sin(theta) + p.k / p.speed_m_s * np.cos(theta)
    return p.end * w * np.cos(theta) + p.k / p.speed_m_s * np.sin(theta)


def natural_frequencies_rad_s(kind: str, p: Pipe, count: int) -> list[float]:
    """The first ``count`` angular frequencies of the lossless pipe [rad/s]: sign changes of
    the real frequency equation on s = i w, refined by bisection."""
    top = (count + 1) * math.pi * p.speed_m_s / p.length_m
    ws = np.linspace(1e-6, top, 400_001)
    values = _lossless(kind, p, ws)
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


def lossless_string(preset):
    """The preset's pipe without its damping (viscous and material), for the tests whose
    theory is the lossless (or only viscously damped) pipe."""
    from dataclasses import replace
    return replace(preset.string, torsional_damping_nm_s_per_rad_m=0.0,
                   axial_damping_n_s_per_m2=0.0, torsional_retardation_time_s=0.0,
                   axial_retardation_time_s=0.0)


def damped_roots(kind: str, p: Pipe, count: int, top=None) -> list[complex]:
    """The first ``count`` roots s [1/s] (Im s > 0) of the pipe with both its dampings, the bit
    off bottom. m s^2 x + c s x = K (1 + eta s) x'': k^2 = s (m s + c) / (K (1 + eta s)), and
    the section's force is K' x' with K' = K (1 + eta s). Axial, the hook force held:
    M s^2 cosh kL + K' k sinh kL = 0. Torsion with the top's dynamic stiffness ``top(s)``
    (torque on the pipe's top -top(s) phi(0); None: the top held), the BHA's I at the
    bottom: I s^2 (K' k cosh kL + top sinh kL) + K' k (K' k sinh kL + top cosh kL) = 0
    (top phi(0) = K' phi'(0), B = top A/(K' k) in phi = A cosh kx + B sinh kx),
    whose limit top -> inf is the held top's I s^2 sinh kL + K' k cosh kL = 0. Newton from the
    lossless pipe's roots with the top held, each one checked to be a
    root of its own (no two alike); the starts also halfway between them, where a free top's
    roots lie."""
    def f(s):
        kp = p.k * (1.0 + p.eta * s)
        k = np.sqrt(s * (p.m * s + p.c) / kp)
        ch, sh = np.cosh(k * p.length_m), np.sinh(k * p.length_m)
        if kind == "axial":
            return p.end * s * s * ch + kp * k * sh
        if top is None:
            return p.end * s * s * sh + kp * k * ch
        t = top(s)
        return p.end * s * s * (kp * k * ch + t * sh) + kp * k * (kp * k * sh + t * ch)
    held = natural_frequencies_rad_s(kind, p, count + 1)
    starts = sorted(held + [0.5 * (a + b) for a, b in zip([0.0, *held], held, strict=False)])
    roots: list[complex] = []
    for w in starts:
        s = complex(-1e-3 * w, w)
        with np.errstate(over="ignore", invalid="ignore"):   # a start that runs off: dropped
            for _ in range(100):
                d = 1e-7 * abs(s)
                s = s - f(s) / ((f(s + d) - f(s - d)) / (2 * d))
        if (np.isfinite(s) and s.imag > 1e-3 * held[0]
                and abs(f(s)) < 1e-9 * abs(f(complex(0.0, abs(s))))
                and all(abs(s - r) > 1e-6 * abs(s) for r in roots)):
            roots.append(complex(s))
    return sorted(roots, key=lambda r: r.imag)[:count]


def energy_ledger(sim, lead: float = 100.0, window: float = 100.0):
    """Run ``sim`` for ``lead`` [t*], then over a window of ``window`` [t*]: (metrics, the
    torsional and the axial energy accounted for: the bit's dissipation, the dashpots', the
    transport's loss, the wall's friction and the change of stored energy), to be compared with
    the work put in at the top."""
    sim.run(lead)
    sim.reset_window()
    e0 = sim.energy()
    m = sim.run(window).metrics
    e1 = sim.energy()
    damped, loss, wall = sim.damped(), sim.transport_loss(), sim.wall_friction()
    rot = m.dissipated_rotation + damped[0] + loss[0] + wall[0] + e1[0] - e0[0]
    ax = m.dissipated_axial + damped[1] + loss[1] + wall[1] + e1[1] - e0[1]
    return m, rot, ax
