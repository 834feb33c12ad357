"""Linear stability of steady drilling on the distributed string, and its natural frequencies.

Linearised about steady drilling (contact kept, g = 1, the delay perturbed), the lumped
Delta(s) of the model contract (section 5) becomes, with the pipe's dynamic stiffnesses
K_t(s) = -m22/m12 (torsion, angle fixed at the top) and K_a(s) = -m21/m11 (axial, force fixed
at the top) from the sections' transfer matrices (``WaveLine.transfer``),

    Delta_d(s) = (s^2 + psi K_a + n psi E)(s^2 + K_t) - k E (s^2 + psi K_a),

which is Delta(s) for K_t = 1, K_a = 0. K_t and K_a have poles (the clamped string's modes), so
the roots are sought of the entire function m11_a m12_t Delta_d(s). With another top boundary
(a control law on the drive's inertia: T_top = -(K/L) phi_top, ``top``), the pipe's bottom
stiffness is K_t = -(L m21 - K m22)/(L m11 - K m12) and the entire function
m11_a (L m11 - K m12) Delta_d(s); K/L infinite is the top held. Root finding: Newton from a
grid over the box [re_min, re_max] x [-im_max, im_max]; the count is checked against the
argument principle on the box's edge (the phase sampled until no step turns it by more than
pi/4); the result says whether they agree. Unlike the lumped Delta, the string has infinitely
many modes along the imaginary axis, so the box's height bounds the search: roots above
im_max are not sought (the default box holds every mode below ~3 Hz on base).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .distributed import StringWaves, WaveLine
from .parameters import Groups, ParameterError
from .roots import central_difference, newton_from_grid, winding_number
from .stability import SteadyState, steady_state
from .top_drive import DriveGroups

ZERO_BOX = 1e-4          # half-width of the box about s = 0 whose roots are s = 0 [1/t*]
# a top boundary: s [1/t*] -> (K, L), K/L the top's dynamic stiffness in units of C
TopBoundary = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def simulated(line: WaveLine) -> WaveLine:
    """The line with the delays the simulation uses ((steps + frac) h + tau: the geometry's,
    but for segments shorter than a step), for comparisons at 1e-3."""
    return WaveLine(line.z, line.simulated_delay, line.steps, line.dashpot, line.h, line.frac,
                    relative=line.relative, tau=line.tau, eta=line.eta, nu=line.nu)


def characteristic(s: np.ndarray | complex, groups: Groups, steady: SteadyState,
                   waves: StringWaves, top: TopBoundary | None = None) -> np.ndarray:
    """m11_a m12_t Delta_d(s) with the top held, or m11_a (L m11 - K m12) Delta_d(s) with the
    top boundary ``top`` (s -> (K, L), ``string_modes``'); entire in s."""
    s = np.asarray(s, dtype=complex)
    n, psi = groups.n, groups.psi
    k = n * (steady.w0 - groups.lam) / (2.0 * math.pi)
    e = 1.0 - np.exp(-s * steady.tau_n0)
    t11, t12, t21, t22 = waves.torsion.transfer(s)
    a11, _, a21, _ = waves.axial.transfer(s)
    s2 = s * s
    axial = s2 * a11 - psi * a21
    if top is None:                        # K infinite: divided through by -K
        d, minus_n = t12, t22
    else:
        kt, lag = top(s)
        d, minus_n = lag * t11 - kt * t12, lag * t21 - kt * t22
        d, minus_n = -d, -minus_n          # the held case's sign, so both agree as K grows
    return (axial + n * psi * e * a11) * (s2 * d - minus_n) - k * e * d * axial


@dataclass(frozen=True)
class StringStability:
    """Roots of Delta_d in the box, rightmost first, without s = 0."""

    steady: SteadyState
    roots: np.ndarray
    box: tuple[float, float, float, float]
    count_argument_principle: int      # roots in the box, s = 0 included
    complete: bool
    roots_at_zero: int = 1             # s = 0's multiplicity (in the count, not in ``roots``)

    @property
    def rightmost(self) -> complex:
        return complex(self.roots[0])

    @property
    def stable(self) -> bool:
        return bool(self.roots.size == 0 or self.roots[0].real < 0.0)

    @property
    def counted(self) -> int:
        """The roots besides s = 0 that the argument principle counts in the box (with a
        law's top: its roots less the law's poles there)."""
        return self.count_argument_principle - self.roots_at_zero


def string_stability(groups: Groups, waves: StringWaves, w0: float, omega0: float, *,
                     re_min: float = -0.5, re_max: float = 5.0, im_max: float = 20.0,
                     top: TopBoundary | None = None) -> StringStability:
    """Every root of Delta_d(s) in [re_min, re_max] x [-im_max, im_max] (see module doc), the
    top held or on the boundary ``top`` (a law's roots among them)."""
    steady = steady_state(groups, w0, omega0)
    if not re_min < 0.0 < re_max or im_max <= 0.0:
        raise ParameterError(f"box [{re_min}, {re_max}] x +-{im_max}: expected re_min < 0 < "
                             "re_max and im_max > 0")
    box = (re_min, re_max, -im_max, im_max)

    def f(s):
        return characteristic(s, groups, steady, waves, top)

    count = winding_number(box, f, "change the box", max_points=2**20)
    roots = np.empty(0, dtype=complex)
    for density in (40, 80, 160):
        roots = find_roots(box, f, density)
        if roots.size == count:
            break
    # s = 0 is a root once with the top held, twice where the top has no static stiffness
    # (a law's top, or a free drive: the string may turn and rise freely as a whole); Newton
    # splits a double root into a pair within ~1e-5 of it: what lies that close is s = 0
    zero_box = ZERO_BOX
    at_zero = winding_number((-zero_box, zero_box, -zero_box, zero_box), f, "change the box")
    nonzero = roots[(np.abs(roots.real) > zero_box) | (np.abs(roots.imag) > zero_box)]
    order = np.lexsort((-nonzero.imag, -np.round(nonzero.real, 9)))
    return StringStability(steady, nonzero[order], box, count,
                           nonzero.size == count - at_zero, at_zero)


def find_roots(box, f: Callable[[np.ndarray], np.ndarray], density: int) -> np.ndarray:
    """The zeros of ``f`` in ``box`` by Newton from a ``density`` x 4 ``density`` grid
    (``roots.newton_from_grid``), its derivative by central difference (step 1e-6), a zero
    where |f| <= 1e-8 (1 + |f'|)(1 + |s|)."""
    return newton_from_grid(box, central_difference(f), density, 4 * density, _is_root)


def _is_root(s: np.ndarray, value: np.ndarray, deriv: np.ndarray) -> np.ndarray:
    return np.abs(value) <= 1e-8 * (1.0 + np.abs(deriv)) * (1.0 + np.abs(s))


def natural_frequencies(waves: StringWaves, psi: float, count: int = 3,
                        omega_max: float = 60.0,
                        top_inertia: float = math.inf) -> tuple[np.ndarray, np.ndarray]:
    """The undamped string's angular frequencies off bottom [1/t*] (bit free, hook force held;
    the rigid-body modes s = 0 excluded); dashpots are ignored. Axial: roots of
    s^2 m11 - psi m21 at s = i omega. Torsional, top speed held (``top_inertia`` inf): roots of
    s^2 m12 - m22; with the top drive's inertia j = ``top_inertia`` [I] at the top under a held
    motor torque (T_top = -j s^2 phi_top, the BHA s^2 phi_bit = T_bit):
    s^2 (m11 - j s^2 m12) - (m21 - j s^2 m22), whose j -> inf limit is the former."""
    tor, ax = waves.torsion.lossless(), waves.axial.lossless()

    def f_t(om):
        m11, m12, m21, m22 = tor.transfer(1j * om)
        if top_inertia == math.inf:
            return (-om * om * m12 - m22).real
        js2 = -top_inertia * om * om
        return (-om * om * (m11 - js2 * m12) - (m21 - js2 * m22)).real

    def f_a(om):
        m11, _, m21, _ = ax.transfer(1j * om)
        return (-om * om * m11 - psi * m21).real

    return _real_roots(f_t, count, omega_max), _real_roots(f_a, count, omega_max)


def _real_roots(f, count: int, omega_max: float) -> np.ndarray:
    """The first ``count`` sign changes of f on (0, omega_max], refined by bisection (poles of
    the dynamic stiffness are not roots: f is the pole-free numerator)."""
    grid = np.linspace(1e-6, omega_max, 200_000)
    values = f(grid)
    idx = np.nonzero(np.sign(values[1:]) != np.sign(values[:-1]))[0][:count]
    roots = []
    for i in idx:
        lo, hi = grid[i], grid[i + 1]
        f_lo = f(np.array([lo]))[0]
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            f_mid = f(np.array([mid]))[0]
            lo, hi, f_lo = (mid, hi, f_mid) if np.sign(f_mid) == np.sign(f_lo) else (lo, mid, f_lo)
        roots.append(0.5 * (lo + hi))
    return np.array(roots)


@dataclass(frozen=True)
class StringMode:
    """A damped mode of the string off bottom: its root s [1/t*] (Im s > 0)."""

    kind: str                    # "torsional" or "axial"
    root: complex

    @property
    def frequency(self) -> float:
        """The damped angular frequency Im s [1/t*]."""
        return float(self.root.imag)

    @property
    def damping_ratio(self) -> float:
        """-Re s / |s| (negative: a growing mode)."""
        return float(-self.root.real / abs(self.root))


@dataclass(frozen=True)
class StringModes:
    """The first ``count`` modes of each family, lowest first; ``complete``: in each family's
    box the Newton search found every root the argument principle counts."""

    torsional: tuple[StringMode, ...]
    axial: tuple[StringMode, ...]
    complete: bool


def top_stiffness(drive: DriveGroups, s: np.ndarray) -> np.ndarray | None:
    """The drive's dynamic stiffness at the top of the string, T = -K(s) phi_top [C], times
    (1 + lag s) so that it is a polynomial: torque mode (a held motor torque) j s^2 (1 + lag s);
    speed mode j s^2 (1 + lag s) + kp s + ki (the PI's torque through the lag); None in
    kinematic mode (the top's angle held: K infinite)."""
    if drive.mode == "kinematic":
        return None
    k = drive.j * s * s * (1.0 + drive.lag * s)
    if drive.mode == "speed":
        k = k + drive.kp * s + drive.ki
    return k


def string_modes(waves: StringWaves, psi: float, drive: DriveGroups, count: int = 5, *,
                 top: Callable[[complex], tuple[complex, complex]] | None = None
                 ) -> StringModes:
    """The string's damped modes off bottom (bit free, hook force held) with ``drive`` at the
    top: roots in Im s > 0 of the torsional s^2 (L m11 - K m12) - (L m21 - K m22) (K, L =
    1 + lag s: ``top_stiffness``; kinematic: s^2 m12 - m22) and of the axial s^2 m11 - psi m21,
    from ``waves``' transfer matrices (build them ``continuous`` for the exact damped pipe).
    The box for each family reaches (count + 1) pi over the travel time along the pipe, above
    the count-th mode for any top between held and free, and left to -that (damping ratios
    up to ~0.7) or to half way to the material's branch point -1/eta. ``top``: another top
    boundary instead of the drive's, s [1/t*] -> (K, L) in units of C, K/L the top's dynamic
    stiffness (a control law at the top, ``control.impedance``), analytic in the box."""
    def f_t(s):
        m11, m12, m21, m22 = waves.torsion.transfer(s)
        if top is not None:
            k, lag = top(s)
        else:
            k = top_stiffness(drive, s)
            if k is None:
                return s * s * m12 - m22
            lag = 1.0 + drive.lag * s
        return s * s * (lag * m11 - k * m12) - (lag * m21 - k * m22)

    def f_a(s):
        m11, _, m21, _ = waves.axial.transfer(s)
        return s * s * m11 - psi * m21

    found, complete = [], True
    for kind, line, f in (("torsional", waves.torsion, f_t), ("axial", waves.axial, f_a)):
        im_max = (count + 1) * math.pi / float(np.sum(line.delay))
        eta = float(np.max(line.eta))
        re_min = -im_max if eta == 0.0 else max(-im_max, -0.5 / eta)
        box = (re_min, 0.25 * im_max, 1e-3 * im_max, im_max)
        n = winding_number(box, f, "the search box for the modes", max_points=2**18)
        roots = np.empty(0, dtype=complex)
        for density in (12, 40, 80):
            roots = find_roots(box, f, density)
            if roots.size >= n:
                break
        complete &= roots.size == n and n >= count
        roots = roots[np.argsort(roots.imag)][:count]
        found.append(tuple(StringMode(kind, complex(r)) for r in roots))
    return StringModes(found[0], found[1], bool(complete))
