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
from dataclasses import dataclass, replace

import numpy as np

from .parameters import ParameterError, RigParameters, check_number
from .string_geometry import StringGeometry
from .tube import Tube

STRING_MODELS = ("lumped", "distributed")
DAMPING_STATIONS = 8        # dashpots per section when it is damped (none when undamped)
# where the stations lie along a section, as fractions of its length: the centres of its
# DAMPING_STATIONS equal parts (the pipe's wall forces and the BHA's are taken there)
STATION_FRACTIONS = tuple((j + 0.5) / DAMPING_STATIONS for j in range(DAMPING_STATIONS))
# the share of the material's damping that the low-pass on every passage carries (tau^2 =
# share eta D); the relative dashpots carry 1 - share/2 of it, so that the two give the
# whole at low frequency (where a standing wave's low-pass loss is half a travelling one's)
PASSAGE_SHARE = 0.2


def check_string_model(name: object) -> str:
    """``lumped`` or ``distributed``, or ParameterError."""
    if name not in STRING_MODELS:
        raise ParameterError(f"string_model = {name!r} is not a string model: expected one of "
                             f"{', '.join(STRING_MODELS)}")
    return str(name)


@dataclass(frozen=True)
class Section(Tube):
    """A uniform tube of the pipe (``Tube``: geometry [m]; material, moduli [Pa] and density
    [kg/m^3], None: ``string_waves``' arguments). Viscous damping per unit length: torsional
    [N m s/rad per m], axial [N s/m per m]; material (Kelvin-Voigt) retardation times [s]: the
    shear stress is G (strain + eta strain rate), likewise E axially. 0 (the defaults):
    lossless. Against the wall: the force per unit length pressing it there [N/m] at the
    centre of each of its ``DAMPING_STATIONS`` equal parts (the stations), and the friction
    coefficients."""

    torsional_damping: float = 0.0
    axial_damping: float = 0.0
    torsional_retardation_s: float = 0.0
    axial_retardation_s: float = 0.0
    wall_n_m: tuple[float, ...] = ()       # the wall's force per length [N/m] at each station
    friction_static: float = 0.0
    friction_dynamic: float = 0.0

    def _check(self) -> None:
        for name in ("torsional_damping", "axial_damping", "torsional_retardation_s",
                     "axial_retardation_s"):
            object.__setattr__(self, name, check_number(name, getattr(self, name),
                                                        low_inclusive=True))


def pipe_sections(geometry: StringGeometry, torsional_damping: float = 0.0,
                  axial_damping: float = 0.0) -> tuple[Section, ...]:
    """The pipe of a preset's geometry (its sections above the BHA, which is rigid), top
    first, each with its material, the viscous damping given, the geometry's material damping
    and, in a hole that rubs, the wall's force at its stations (the soft string hanging off
    bottom: ``StringGeometry.wall_forces_n_m``) and the friction coefficients."""
    well = geometry.well
    rubs = well is not None and well.rubs
    return tuple(Section(x.length_m, x.od_m, x.id_m, torsional_damping, axial_damping,
                         geometry.torsional_retardation_time_s,
                         geometry.axial_retardation_time_s,
                         tuple(geometry.wall_forces_n_m(i, STATION_FRACTIONS)) if rubs else (),
                         well.friction_static if rubs else 0.0,
                         well.friction_dynamic if rubs else 0.0,
                         shear_modulus_pa=geometry.shear_modulus(x),
                         young_modulus_pa=geometry.young_modulus(x),
                         steel_density_kg_m3=geometry.density(x))
                 for i, x in enumerate(geometry.pipe()))


@dataclass(frozen=True)
class WaveLine:
    """One wave family (torsional or axial) of the string, dimensionless, top segment first.

    z: impedance of each segment; delay: its travel time [t*]; steps, frac: the travel time in
    steps, whole and fraction (steps + frac = delay/h; a segment shorter than a step is
    simulated as one step, steps 1 and frac 0); dashpot: at the segment's bottom (the last one
    acts on the BHA). relative: a dashpot [C t*] across the segment, between its two ends (in
    parallel with its stiffness: the material's Kelvin-Voigt damping lumped at the stations);
    tau: the time constant of a low-pass every passage through the segment goes through, the
    ring buffer's travel time shortened by tau (``distributed_kernel``): the share of the
    material's damping that acts on short waves, which dashpots at the stations cannot reach
    where every station is a node. eta: the material's retardation time [t*] (stress
    G (strain + eta strain rate)) and nu: viscous damping per unit length over inertia per
    unit length [1/t*], both continuous along the segment: the theory's exact pipe
    (``string_waves(..., continuous=True)``); the simulation's lines carry the damping as
    ``dashpot``, ``relative`` and ``tau`` instead (eta, nu 0).
    """

    z: np.ndarray
    delay: np.ndarray
    steps: np.ndarray
    dashpot: np.ndarray
    h: float
    frac: np.ndarray | None = None
    relative: np.ndarray | None = None
    tau: np.ndarray | None = None
    eta: np.ndarray | None = None
    nu: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name in ("frac", "relative", "tau", "eta", "nu"):
            if getattr(self, name) is None:
                object.__setattr__(self, name, np.zeros(np.size(self.z)))

    @property
    def simulated_delay(self) -> np.ndarray:
        """The travel times the simulation gives at low frequency, (steps + frac) h + tau [t*]
        (the low-pass's group delay is tau)."""
        return (self.steps + self.frac) * self.h + self.tau

    @property
    def delay_error(self) -> float:
        """Largest relative error of a segment's simulated travel time vs delay."""
        return float(np.max(np.abs(self.simulated_delay - self.delay) / self.delay))

    def lossless(self) -> WaveLine:
        """The same line without any damping (the travel times the geometry's)."""
        return WaveLine(self.z, self.delay, self.steps, np.zeros(np.size(self.z)), self.h,
                        self.frac)

    def transfer(self, s: complex | np.ndarray) -> tuple:
        """Top-to-bottom transfer matrix (m11, m12, m21, m22) of (angle, torque) at Laplace
        variable s. A segment: with r = sqrt(s (s + nu)), q = sqrt(1 + eta s), g = D r / q and
        W = z r q (G J gamma of the damped tube), [[cosh g, -sinh g / W], [-W sinh g, cosh g]]
        (lossless: g = s D, W = z s); with a low-pass tau (the simulation's lines), W = z s
        and g = s (D - tau) + log(1 + s tau); then its relative dashpot in parallel; a dashpot
        [[1, 0], [-c s, 1]]. Torque is the one the part above exerts on the part below. Even
        in r and in q, so the branches do not matter; entire in s but for the branch point
        s = -1/eta far to the left."""
        s = np.asarray(s, dtype=complex)
        m11, m12, m21, m22 = np.ones_like(s), np.zeros_like(s), np.zeros_like(s), np.ones_like(s)
        for z, d, c, rel, tau, eta, nu in zip(self.z, self.delay, self.dashpot, self.relative,
                                              self.tau, self.eta, self.nu, strict=True):
            if tau > 0.0:              # the buffer's D - tau, then the low-pass 1/(1 + s tau)
                with np.errstate(all="ignore"):
                    g_over_s = np.where(s == 0.0, d, d - tau + np.log1p(s * tau) / s)
                g = s * g_over_s
                sh_over_g = np.sinc(1j * g / np.pi)
                a11, a12 = np.cosh(g), -sh_over_g * g_over_s / z
                a21, a22 = -z * s * s * g_over_s * sh_over_g, a11
            else:
                q2 = 1.0 + eta * s
                r = np.sqrt(s * (s + nu))
                g = d * r / np.sqrt(q2)
                ch = np.cosh(g)
                sh_over_g = np.sinc(1j * g / np.pi)            # sinh(g)/g, 1 at g = 0
                a11, a12 = ch, -sh_over_g * d / (z * q2)      # sinh g / W = (sinh g/g) D/(z q^2)
                a21, a22 = -z * d * r * r * sh_over_g, ch      # W sinh g = z D r^2 sinh(g)/g
            if rel > 0.0:                                      # T = T_tube + rel s (phi1 - phi2)
                rs = rel * s
                e = 1.0 - rs * a12
                n11, n12 = (a11 - rs * a12) / e, a12 / e
                a21, a22 = (a21 + (a22 - 1.0) * rs * (n11 - 1.0),
                            a22 * (1.0 + rs * n12) - rs * n12)
                a11, a12 = n11, n12
            m11, m12, m21, m22 = (a11 * m11 + a12 * m21, a11 * m12 + a12 * m22,
                                  a21 * m11 + a22 * m21, a21 * m12 + a22 * m22)
            m21, m22 = m21 - c * s * m11, m22 - c * s * m12
        return m11, m12, m21, m22


@dataclass(frozen=True)
class BhaContact:
    """The rigid BHA against the wall, SI: the wall's whole force on it [N] (the soft string's
    n integrated over its sections), the radius it rubs at [m] (its sections' radii weighted
    by their share of that force, so that its break-off torque is mu_s sum n_i L_i r_i and its
    axial drag mu sum n_i L_i exactly) and the friction coefficients (the well's)."""

    normal_force_n: float
    radius_m: float
    friction_static: float
    friction_dynamic: float


@dataclass(frozen=True)
class WallFriction:
    """The wall's Coulomb friction at the stations, aligned with the segments (the station at
    each segment's bottom; 0 where there is none; the last segment's bottom is the rigid
    BHA's one contact, ``BhaContact``): the most the wall holds, static and sliding
    [F*] (mu n L_part), and kappa = r/L* (the pipe's radius), with sigma = C/(F* L*): a torque
    tau [C] is the tangential force tau sigma/kappa [F*] and a turning speed omega [1/t*] the
    sliding speed kappa omega [L*/t*] (``distributed_kernel._junctions_wall``, the BHA's in
    ``distributed_kernel._bha_on_wall``)."""

    static: np.ndarray
    dynamic: np.ndarray
    kappa: np.ndarray
    sigma: float

    def forces(self, v: float, omega: float) -> tuple[np.ndarray, np.ndarray]:
        """Each station's friction sliding at axial speed ``v`` [L*/t*] and turning speed
        ``omega`` [1/t*]: (torque [C], axial force [F*]), against the motion."""
        speed = np.hypot(v, self.kappa * omega)
        with np.errstate(invalid="ignore", divide="ignore"):
            share_t = np.where(speed > 0.0, self.kappa * omega / speed, 0.0)
            share_a = np.where(speed > 0.0, v / speed, 0.0)
        return (self.dynamic * share_t * self.kappa / self.sigma, self.dynamic * share_a)


@dataclass(frozen=True)
class StringWaves:
    """The distributed string, dimensionless (torques [C], forces [F*], times [t*]); ``wall``:
    the friction against the wall (None: none)."""

    torsion: WaveLine
    axial: WaveLine
    h: float
    wall: WallFriction | None = None

    @property
    def pipe_inertia(self) -> float:
        """Polar inertia of the pipe over the BHA's, sum of z D."""
        return float(np.sum(self.torsion.z * self.torsion.delay))

    def steady_top_torque(self, bit_torque: float, omega0: float, v0: float = 0.0) -> float:
        """The torque at the top of the string turning steadily at ``omega0`` [1/t*] (and
        moving down at ``v0`` [L*/t*]) with ``bit_torque`` [C] on the BHA: that plus every
        dashpot's c omega0 and the wall's sliding friction (the relative dashpots and the
        low-passes carry nothing in a steady turn)."""
        wall = 0.0 if self.wall is None else float(np.sum(self.wall.forces(v0, omega0)[0]))
        return bit_torque + float(np.sum(self.torsion.dashpot)) * omega0 + wall

    @property
    def pipe_mass(self) -> float:
        """Mass of the pipe over the BHA's, times psi: sum of z_a D_a (psi m_p/M)."""
        return float(np.sum(self.axial.z * self.axial.delay))


def string_waves(params: RigParameters, sections: tuple[Section, ...], h: float, *,
                 shear_modulus_pa: float = 77e9, young_modulus_pa: float = 200e9,
                 steel_density_kg_m3: float = 8000.0,
                 stations: int = DAMPING_STATIONS, continuous: bool = False,
                 bha: BhaContact | None = None) -> StringWaves:
    """The dimensionless wave lines of ``sections`` (top first) with the scales of ``params``
    (t* = sqrt(I/C) from the lumped C, I), at step ``h`` [t*]. ``continuous``: the theory's
    exact pipe (one segment per section, viscous damping continuous along it, no stations),
    whose ``transfer`` the modes and the tests use; otherwise the simulation's lines.
    ``bha``: the rigid BHA's contact with the wall (None: it does not rub)."""
    if not sections:
        raise ParameterError("sections: expected at least one pipe section")
    sc = params.scales
    ts, c_scale = sc.time_s, sc.stiffness_nm_per_rad
    bha_rubs = bha is not None and bha.friction_static > 0.0 and bha.normal_force_n > 0.0
    rubs = not continuous and (bha_rubs or any(sec.friction_static > 0.0 and any(sec.wall_n_m)
                                               for sec in sections))
    if rubs:          # a BHA rubbing below a pipe that does not: the pipe's stations hold 0
        sections = tuple(sec if sec.wall_n_m else replace(sec, wall_n_m=(0.0,) * stations)
                         for sec in sections)
    if rubs and any(len(sec.wall_n_m) != stations for sec in sections):
        raise ParameterError(f"sections: the wall's forces are given at {DAMPING_STATIONS} "
                             f"stations a section; expected stations = {DAMPING_STATIONS}")
    lines = []
    for modulus_name, default_modulus, prop, damp, retard, imp_scale in (
            ("shear_modulus_pa", shear_modulus_pa, "polar_moment_m4", "torsional_damping",
             "torsional_retardation_s", c_scale * ts),
            ("young_modulus_pa", young_modulus_pa, "area_m2", "axial_damping",
             "axial_retardation_s", sc.force_n * ts / sc.length_m)):
        z, delay, steps, frac, dash, rel, tau, eta, nu = [], [], [], [], [], [], [], [], []
        for sec in sections:
            modulus = getattr(sec, modulus_name) or default_modulus
            rho = sec.steel_density_kg_m3 or steel_density_kg_m3
            speed = math.sqrt(modulus / rho)
            per_length = getattr(sec, damp)
            e = getattr(sec, retard) / ts
            # the stations: where the pipe is damped or rubs (then in both families alike,
            # so the wall's friction couples the axial and the torsional line there)
            k = 0 if continuous or (per_length == 0.0 and e == 0.0 and not rubs) else stations
            # segment ends: 0, (j - 1/2)/k (the stations, at the centres of k equal parts), 1
            ends = [0.0, *((j + 0.5) / k for j in range(k)), 1.0]
            for j in range(k + 1):
                d = (ends[j + 1] - ends[j]) * sec.length_m / speed / ts
                lag = 0.0 if continuous else math.sqrt(PASSAGE_SHARE * e * d)
                if lag > 0.0 and d - lag < h:
                    raise ParameterError(
                        f"{retard} = {getattr(sec, retard)!r} s is too large for a section of "
                        f"{sec.length_m!r} m at this step: the material's low-pass "
                        f"({lag * ts:.3g} s) must be shorter than the travel time of each part "
                        f"of it ({d * ts:.3g} s) by a step")
                whole = max(1, math.floor((d - lag) / h))
                z.append(getattr(sec, prop) * math.sqrt(modulus * rho) / imp_scale)
                delay.append(d)
                steps.append(whole)
                frac.append(min(max((d - lag) / h - whole, 0.0), 1.0 - 1e-12))
                dash.append(per_length * sec.length_m / k / imp_scale if j < k else 0.0)
                # Kelvin-Voigt: eta times the part's stiffness z/D across each whole part
                # between two stations (k/(k - 1) of it: the end halves carry none), less what
                # the low-pass gives at low frequency
                whole_part = 0 < j < k and k > 1
                rel.append((1.0 - 0.5 * PASSAGE_SHARE) * e * z[-1] / d * k / (k - 1)
                           if whole_part else 0.0)
                tau.append(lag)
                eta.append(e if continuous else 0.0)
                nu.append(per_length / (rho * getattr(sec, prop)) * ts if continuous else 0.0)
        lines.append(WaveLine(np.array(z), np.array(delay), np.array(steps, dtype=np.int64),
                              np.array(dash), h, np.array(frac), np.array(rel), np.array(tau),
                              np.array(eta), np.array(nu)))
    return StringWaves(lines[0], lines[1], h,
                       _wall(params, sections, stations, bha if bha_rubs else None)
                       if rubs else None)


def _wall(params: RigParameters, sections: tuple[Section, ...], k: int,
          bha: BhaContact | None) -> WallFriction:
    """The wall's friction at the stations (k a section), aligned with the segments: section
    by section, k segments ending at a station, then the one ending at the next section (the
    last one's: the BHA's contact, or none)."""
    sc = params.scales
    static, dynamic, kappa = [], [], []
    for sec in sections:
        for j in range(k + 1):
            if j < k:
                held = sec.wall_n_m[j] * sec.length_m / k / sc.force_n      # n L_part [F*]
                static.append(sec.friction_static * held)
                dynamic.append(sec.friction_dynamic * held)
                kappa.append(0.5 * sec.od_m / sc.length_m)
            else:
                static.append(0.0)
                dynamic.append(0.0)
                kappa.append(1.0)
    if bha is not None:
        held = bha.normal_force_n / sc.force_n
        static[-1], dynamic[-1] = bha.friction_static * held, bha.friction_dynamic * held
        kappa[-1] = bha.radius_m / sc.length_m
    return WallFriction(np.array(static), np.array(dynamic), np.array(kappa),
                        sc.stiffness_nm_per_rad / (sc.force_n * sc.length_m))


def geometry_waves(params: RigParameters, geometry: StringGeometry, h: float,
                   young_modulus_pa: float | None = None, torsional_damping: float | None = None,
                   axial_damping: float | None = None, continuous: bool = False) -> StringWaves:
    """The wave lines of a preset's pipe (its sections above the BHA) at step ``h`` [t*];
    viscous damping per unit length (torsional [N m s/rad per m], axial [N s/m per m]) and
    Young's modulus [Pa] None: the geometry's. ``continuous``: the theory's exact pipe
    (``string_waves``)."""
    if torsional_damping is None:
        torsional_damping = geometry.torsional_damping_nm_s_per_rad_m
    if axial_damping is None:
        axial_damping = geometry.axial_damping_n_s_per_m2
    sections = pipe_sections(geometry, torsional_damping, axial_damping)
    if young_modulus_pa is not None:
        sections = tuple(replace(x, young_modulus_pa=young_modulus_pa) for x in sections)
    return string_waves(params, sections, h, shear_modulus_pa=geometry.shear_modulus_pa,
                        young_modulus_pa=geometry.young_modulus_pa,
                        steel_density_kg_m3=geometry.steel_density_kg_m3, continuous=continuous,
                        bha=bha_contact(geometry))


def bha_contact(geometry: StringGeometry) -> BhaContact | None:
    """The rigid BHA's contact with the wall (None: the well does not rub): the soft string's
    wall force hanging off bottom over the BHA's sections, integrated by the midpoint rule at
    the pipe's ``DAMPING_STATIONS`` stations a section (exact in straight hole)."""
    well = geometry.well
    if well is None or not well.rubs:
        return None
    force = moment = 0.0
    for i, part in enumerate(geometry.parts()):
        if part.bha:
            held = (sum(geometry.wall_forces_n_m(i, STATION_FRACTIONS)) * part.length_m
                    / DAMPING_STATIONS)
            force += held
            moment += held * 0.5 * part.od_m
    if force <= 0.0:
        return None
    return BhaContact(force, moment / force, well.friction_static, well.friction_dynamic)
