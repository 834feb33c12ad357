"""Steady drilling (model contract, section 4) and the roots of its characteristic function
(section 5).

Root finding: every root of Delta(s) with Re s >= re_min lies in the disc |s| <= R, with R from
the bound |s|^4 <= |s|^2 (1 + (n psi + k) e_max) + n psi e_max, e_max = 1 + exp(-re_min tau_n0).
The box [re_min, R] x [-R, R] therefore holds them all. Newton's method is started from a grid
over the box, the distinct converged roots are kept, and their number is checked against the
argument principle (the winding number of Delta along the box edge, sampled until no step turns
the phase by more than pi/4). A mismatch refines the grid; the result says whether the counts
agreed, so a caller knows none were missed. A box expected to hold more than MAX_ROOTS roots
(a re_min far left, or a long delay at low speed) is refused with the re_min or speed that works.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .parameters import Groups, ParameterError, check_number
from .roots import newton_from_grid, winding_number


class NoSteadyDrilling(ValueError):
    """w0 <= lambda: the weight cannot beat full wear-flat friction, so there is no drilling."""


@dataclass(frozen=True)
class SteadyState:
    """The trivial solution, dimensionless (model contract, section 4)."""

    w0: float
    omega0: float
    delta_n0: float   # depth of cut per blade [L*]
    v0: float         # rate of penetration [L*/t*]
    t0: float         # torque on bit, equal to the string torque [C]
    tau_n0: float     # delay: time for one sector [t*]


def steady_state(groups: Groups, w0: float, omega0: float) -> SteadyState:
    """Steady drilling at (w0, omega0), or NoSteadyDrilling when w0 <= lambda."""
    w0 = check_number("w0", w0, low=None)
    omega0 = check_number("omega0", omega0)
    if w0 <= groups.lam:
        raise NoSteadyDrilling(
            f"no steady drilling solution: w0 = {w0:g} <= lambda = {groups.lam:g}; the weight "
            "cannot overcome full wear-flat friction, so the bit rotates on its wear flats "
            "without penetrating")
    return SteadyState(w0=w0, omega0=omega0, delta_n0=(w0 - groups.lam) / groups.n,
                       v0=omega0 * (w0 - groups.lam) / (2.0 * math.pi),
                       t0=w0 - (1.0 - groups.beta) * groups.lam,
                       tau_n0=2.0 * math.pi / (groups.n * omega0))


def characteristic(s: np.ndarray | complex, groups: Groups, steady: SteadyState):
    """Delta(s) = (s^2 + 1)(s^2 + n psi E) - k s^2 E, E = 1 - exp(-s tau_n0), and Delta'(s)."""
    n, psi = groups.n, groups.psi
    k = n * (steady.w0 - groups.lam) / (2.0 * math.pi)
    tau = steady.tau_n0
    ex = np.exp(-s * tau)
    e = 1.0 - ex
    de = tau * ex
    s2 = s * s
    value = (s2 + 1.0) * (s2 + n * psi * e) - k * s2 * e
    deriv = 2.0 * s * (s2 + n * psi * e) + (s2 + 1.0) * (2.0 * s + n * psi * de) \
        - k * (2.0 * s * e + s2 * de)
    return value, deriv


@dataclass(frozen=True)
class StabilityResult:
    """Roots of Delta(s) in the box, rightmost first, without the ever-present root s = 0."""

    steady: SteadyState
    roots: np.ndarray          # complex, sorted by decreasing real part
    re_min: float              # left edge of the search box [1/t*]
    radius: float              # every root with Re s >= re_min has |s| <= radius
    count_argument_principle: int   # roots in the box, s = 0 included, by the winding number
    complete: bool             # True when the found roots match that count

    @property
    def stable(self) -> bool:
        return bool(self.roots.size == 0 or self.roots[0].real < 0.0)

    @property
    def rightmost(self) -> complex:
        return complex(self.roots[0])


MAX_ROOTS = 150     # the most roots a search box may be expected to hold (~5 s of search)


def _radius(groups: Groups, steady: SteadyState, re_min: float) -> float:
    """R: every root with Re s >= re_min has |s| <= R (inf when exp(-re_min tau) overflows)."""
    x = -re_min * steady.tau_n0
    e_max = 1.0 + math.exp(x) if x < 700.0 else math.inf
    k = groups.n * (steady.w0 - groups.lam) / (2.0 * math.pi)
    a = 1.0 + (groups.n * groups.psi + abs(k)) * e_max
    b = groups.n * groups.psi * e_max
    return 1.05 * math.sqrt(0.5 * (a + math.sqrt(a * a + 4.0 * b)))


def _expected_roots(groups: Groups, steady: SteadyState, re_min: float) -> float:
    """About how many roots the box holds: the delay spaces them 2 pi/tau_n0 apart along
    each of its 2R-long vertical lines (two families), so about R tau_n0/pi (checked
    against the winding number from 7 to 1850 roots)."""
    return _radius(groups, steady, re_min) * steady.tau_n0 / math.pi


def _three_digits(x: float, rounding) -> float:
    """x to three significant digits, rounded by ``rounding`` (math.trunc, math.ceil)."""
    scale = 10.0 ** (2 - math.floor(math.log10(abs(x))))
    return rounding(x * scale) / scale


def _check_box(groups: Groups, steady: SteadyState, re_min: float) -> None:
    """Refuse a search whose box would hold more than MAX_ROOTS roots, saying what works."""
    if _expected_roots(groups, steady, re_min) <= MAX_ROOTS:
        return
    tau = steady.tau_n0
    if _expected_roots(groups, steady, -1e-6) > MAX_ROOTS:
        lo, hi = math.log(steady.omega0), math.log(1e3)     # bisect for the lowest speed
        for _ in range(100):
            mid = 0.5 * (lo + hi)
            at = steady_state(groups, steady.w0, math.exp(mid))
            lo, hi = (mid, hi) if _expected_roots(groups, at, -1e-3) > MAX_ROOTS else (lo, mid)
        lowest = _three_digits(math.exp(hi), math.ceil)
        raise ParameterError(
            f"stability: omega0 = {steady.omega0:g} is too low for the root search: the delay "
            f"tau_n0 = 2 pi/(n omega0) = {tau:.4g} t* packs more than {MAX_ROOTS} roots into any "
            f"box that holds the unstable ones; the search works for omega0 >= {lowest:g} "
            "at this weight, with re_min = -0.001")
    lo, hi = max(re_min, -700.0 / tau), -1e-6  # bisect for the widest box allowed
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _expected_roots(groups, steady, mid) > MAX_ROOTS else (lo, mid)
    raise ParameterError(
        f"stability: re_min = {re_min:g} at omega0 = {steady.omega0:g} asks for a box of "
        f"radius {_radius(groups, steady, re_min):.3g} holding about "
        f"{_expected_roots(groups, steady, re_min):.3g} roots (exp(-re_min tau_n0) with "
        f"tau_n0 = {tau:.4g} t*); the search is made for at most {MAX_ROOTS}: use "
        f"re_min >= {_three_digits(hi, math.trunc):g}")


def stability(groups: Groups, w0: float, omega0: float, *, re_min: float = -0.5) -> StabilityResult:
    """All roots of Delta(s) with Re s >= re_min, found and counted as the module doc says.

    Refused (ParameterError, saying what works) when the box would hold more than MAX_ROOTS
    roots: a re_min far left of 0, or a very low omega0 (a long delay packs the roots)."""
    steady = steady_state(groups, w0, omega0)
    re_min = check_number("re_min", re_min, low=None, high=-1e-6)
    _check_box(groups, steady, re_min)
    radius = _radius(groups, steady, re_min)
    box = (re_min, radius, -radius, radius)
    count = winding_number(box, lambda path: characteristic(path, groups, steady)[0],
                           "change re_min")
    roots = np.empty(0, dtype=complex)
    for density in (40, 80, 160, 320):
        roots = newton_from_grid(box, lambda s: characteristic(s, groups, steady), density,
                                 2 * density, _is_root)
        if roots.size == count:
            break
    nonzero = roots[np.abs(roots) > 1e-7]
    order = np.lexsort((-nonzero.imag, -np.round(nonzero.real, 9)))   # pairs: +i first
    return StabilityResult(steady=steady, roots=nonzero[order], re_min=re_min, radius=radius,
                           count_argument_principle=count, complete=roots.size == count)


def _is_root(s: np.ndarray, value: np.ndarray, deriv: np.ndarray) -> np.ndarray:
    """|Delta(s)| <= 1e-9 (1 + |s|^4): Delta grows as s^4."""
    return np.abs(value) <= 1e-9 * (1.0 + np.abs(s) ** 4)
