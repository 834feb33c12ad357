"""The distributed drill string: uniform sections carrying torsional and axial waves.

The pipe is a chain of uniform sections (GJ phi_xx = rho J phi_tt, EA u_xx = rho A u_tt); the
collars stay the rigid BHA (I, M) at its end, so the bit equations are the lumped model's with
C (phi_td - phi) replaced by the pipe's bottom torque and W0 by the pipe's bottom force
(msg_docs/model.md, "The distributed string"). A lossless uniform section is an exact delay of
its two Riemann invariants a = T + Z omega (down) and b = T - Z omega (up); with the step h, a
segment of travel time D = (N + f) h (N whole, 0 <= f < 1) is a ring buffer of N + 1 step means,
and what arrives in a step is the exact mean of the departures over the step D earlier, the two
step means it straddles weighted 1 - f and f. Viscous damping per unit
length is lumped into ``stations`` dashpots per section, at the centres of equal parts of it
(the midpoint rule: the damped modes' decay rates within ~0.5 % of the continuously damped
pipe's at 8 stations, where dashpots at the parts' ends were 16 % off for the first mode).
This module turns SI geometry into that dimensionless description and gives the sections'
transfer matrices (frequency domain) for the theory.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .parameters import ParameterError, RigParameters, StringGeometry, check_number

STRING_MODELS = ("lumped", "distributed")
DAMPING_STATIONS = 8        # dashpots per section when it is damped (none when undamped)


def check_string_model(name: object) -> str:
    """``lumped`` or ``distributed``, or ParameterError."""
    if name not in STRING_MODELS:
        raise ParameterError(f"string_model = {name!r} is not a string model: expected one of "
                             f"{', '.join(STRING_MODELS)}")
    return str(name)


@dataclass(frozen=True)
class Section:
    """A uniform tube of the pipe, SI. Damping per unit length: torsional [N m s/rad per m],
    axial [N s/m per m]; 0 (the default) is a lossless section."""

    length_m: float
    od_m: float
    id_m: float
    torsional_damping: float = 0.0
    axial_damping: float = 0.0

    def __post_init__(self) -> None:
        for name in ("length_m", "od_m"):
            object.__setattr__(self, name, check_number(name, getattr(self, name)))
        for name in ("id_m", "torsional_damping", "axial_damping"):
            object.__setattr__(self, name, check_number(name, getattr(self, name),
                                                        low_inclusive=True))
        if self.id_m >= self.od_m:
            raise ParameterError(f"id_m = {self.id_m!r} is out of range: expected < od_m")

    @property
    def polar_moment_m4(self) -> float:
        return math.pi / 32.0 * (self.od_m**4 - self.id_m**4)

    @property
    def area_m2(self) -> float:
        return math.pi / 4.0 * (self.od_m**2 - self.id_m**2)


def pipe_sections(geometry: StringGeometry, torsional_damping: float = 0.0,
                  axial_damping: float = 0.0) -> tuple[Section, ...]:
    """The pipe of a preset's geometry as one section (the collars are the rigid BHA)."""
    return (Section(geometry.pipe_length_m, geometry.pipe_od_m, geometry.pipe_id_m,
                    torsional_damping, axial_damping),)


@dataclass(frozen=True)
class WaveLine:
    """One wave family (torsional or axial) of the string, dimensionless, top segment first.

    z: impedance of each segment; delay: its travel time [t*]; steps, frac: the travel time in
    steps, whole and fraction (steps + frac = delay/h; a segment shorter than a step is
    simulated as one step, steps 1 and frac 0); dashpot: at the segment's bottom (the last one
    acts on the BHA)."""

    z: np.ndarray
    delay: np.ndarray
    steps: np.ndarray
    dashpot: np.ndarray
    h: float
    frac: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.frac is None:
            object.__setattr__(self, "frac", np.zeros(np.size(self.steps)))

    @property
    def simulated_delay(self) -> np.ndarray:
        """The travel times the simulation uses, (steps + frac) h [t*]."""
        return (self.steps + self.frac) * self.h

    @property
    def delay_error(self) -> float:
        """Largest relative error of a segment's simulated travel time vs delay."""
        return float(np.max(np.abs(self.simulated_delay - self.delay) / self.delay))

    def transfer(self, s: complex | np.ndarray) -> tuple:
        """Top-to-bottom transfer matrix (m11, m12, m21, m22) of (angle, torque) at Laplace
        variable s: segment [[cosh sD, -sinh sD/(z s)], [-z s sinh sD, cosh sD]], dashpot
        [[1, 0], [-c s, 1]]. Torque is the one the part above exerts on the part below."""
        s = np.asarray(s, dtype=complex)
        m11, m12, m21, m22 = np.ones_like(s), np.zeros_like(s), np.zeros_like(s), np.ones_like(s)
        for z, d, c in zip(self.z, self.delay, self.dashpot, strict=True):
            ch, sh = np.cosh(s * d), np.sinh(s * d)
            sh_over_s = d * np.sinc(1j * s * d / np.pi)        # sinh(sD)/s, D at s = 0
            a11, a12, a21, a22 = ch, -sh_over_s / z, -z * s * sh, ch
            m11, m12, m21, m22 = (a11 * m11 + a12 * m21, a11 * m12 + a12 * m22,
                                  a21 * m11 + a22 * m21, a21 * m12 + a22 * m22)
            m21, m22 = m21 - c * s * m11, m22 - c * s * m12
        return m11, m12, m21, m22


@dataclass(frozen=True)
class StringWaves:
    """The distributed string, dimensionless (torques [C], forces [F*], times [t*])."""

    torsion: WaveLine
    axial: WaveLine
    h: float

    @property
    def pipe_inertia(self) -> float:
        """Polar inertia of the pipe over the BHA's, sum of z D."""
        return float(np.sum(self.torsion.z * self.torsion.delay))

    @property
    def pipe_mass(self) -> float:
        """Mass of the pipe over the BHA's, times psi: sum of z_a D_a (psi m_p/M)."""
        return float(np.sum(self.axial.z * self.axial.delay))


def string_waves(params: RigParameters, sections: tuple[Section, ...], h: float, *,
                 shear_modulus_pa: float = 77e9, young_modulus_pa: float = 200e9,
                 steel_density_kg_m3: float = 8000.0,
                 stations: int = DAMPING_STATIONS) -> StringWaves:
    """The dimensionless wave lines of ``sections`` (top first) with the scales of ``params``
    (t* = sqrt(I/C) from the lumped C, I), at step ``h`` [t*]."""
    if not sections:
        raise ParameterError("sections: expected at least one pipe section")
    sc = params.scales
    ts, c_scale = sc.time_s, sc.stiffness_nm_per_rad
    rho = steel_density_kg_m3
    lines = []
    for modulus, prop, damp, imp_scale in (
            (shear_modulus_pa, "polar_moment_m4", "torsional_damping", c_scale * ts),
            (young_modulus_pa, "area_m2", "axial_damping", sc.force_n * ts / sc.length_m)):
        speed = math.sqrt(modulus / rho)
        z, delay, steps, frac, dash = [], [], [], [], []
        for sec in sections:
            k = stations if getattr(sec, damp) > 0.0 else 0
            # segment ends: 0, (j - 1/2)/k (the dashpots, at the centres of k equal parts), 1
            ends = [0.0, *((j + 0.5) / k for j in range(k)), 1.0]
            for j in range(k + 1):
                d = (ends[j + 1] - ends[j]) * sec.length_m / speed / ts
                whole = max(1, math.floor(d / h))
                z.append(getattr(sec, prop) * math.sqrt(modulus * rho) / imp_scale)
                delay.append(d)
                steps.append(whole)
                frac.append(min(max(d / h - whole, 0.0), 1.0 - 1e-12))
                dash.append(getattr(sec, damp) * sec.length_m / k / imp_scale if j < k else 0.0)
        lines.append(WaveLine(np.array(z), np.array(delay), np.array(steps, dtype=np.int64),
                              np.array(dash), h, np.array(frac)))
    return StringWaves(lines[0], lines[1], h)


def geometry_waves(params: RigParameters, geometry: StringGeometry, h: float,
                   young_modulus_pa: float = 200e9, torsional_damping: float | None = None,
                   axial_damping: float | None = None) -> StringWaves:
    """The wave lines of a preset's pipe (one section) at step ``h`` [t*]; damping per unit
    length (torsional [N m s/rad per m], axial [N s/m per m]) None: the geometry's."""
    if torsional_damping is None:
        torsional_damping = geometry.torsional_damping_nm_s_per_rad_m
    if axial_damping is None:
        axial_damping = geometry.axial_damping_n_s_per_m2
    return string_waves(params, pipe_sections(geometry, torsional_damping, axial_damping), h,
                        shear_modulus_pa=geometry.shear_modulus_pa,
                        young_modulus_pa=young_modulus_pa,
                        steel_density_kg_m3=geometry.steel_density_kg_m3)
