"""The hole the string hangs in: a survey and the friction of the string against the wall.

A survey is rows of measured depth [m], inclination [deg] and azimuth [deg], from the surface
(measured depth 0, the string's top) to at least the bit. Between two rows the hole is a
circular arc (the minimum-curvature method), so the unit tangent t(s) and its rate dt/ds (the
curvature vector) are known everywhere. No survey: a vertical hole.

The soft-string model (Johancsik et al., 1984): a string without bending stiffness lies on the
wall, pressed against it per unit length by n = |T dt/ds + w (g - (g.t) t)|, T the effective
tension, w the buoyed weight per unit length and g the downward unit vector: the weight's
component across the hole and the tension pulling the string to the inside of a bend. Straight
and inclined, n = w sin(inclination). The friction coefficients are Coulomb's: the wall takes at
most mu_s n per unit length from a string at rest against it and mu_d n from one sliding, against
the sliding velocity (axial and tangential together).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from .parameters import ParameterError, check_number

# what a formation may change, with the range each takes (the node's parameter table's)
ROCK = {"intrinsic_specific_energy_pa": (1e7, 5e8), "contact_stress_pa": (0.0, 5e8),
        "friction_coefficient": (0.05, 1.5)}


@dataclass(frozen=True)
class Formation:
    """A layer of rock from ``top_m`` [m, measured depth] down to the next layer's top: the
    rock and bit-rock parameters that change there (None: as above it; the first layer's
    above is the preset's ``bit`` section): intrinsic specific energy epsilon [Pa], wear-flat
    contact stress sigma [Pa], bit-rock friction coefficient mu [-]."""

    top_m: float
    intrinsic_specific_energy_pa: float | None = None
    contact_stress_pa: float | None = None
    friction_coefficient: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "top_m", check_number("top_m", self.top_m, low_inclusive=True))
        for name, (low, high) in ROCK.items():
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, check_number(
                    name, value, low=low, low_inclusive=low == 0.0, high=high))
        if all(getattr(self, name) is None for name in ROCK):
            raise ParameterError(f"formation at {self.top_m:g} m changes nothing: expected at "
                                 f"least one of {', '.join(ROCK)}")

    def changes(self) -> dict[str, float]:
        """The rock values this formation gives (``ROCK`` names)."""
        return {n: getattr(self, n) for n in ROCK if getattr(self, n) is not None}

    def given(self) -> dict[str, float]:
        """The fields given (top_m and what changes), for records."""
        return {"top_m": self.top_m, **self.changes()}


@dataclass(frozen=True)
class Well:
    """The hole: ``survey`` rows (measured depth [m], inclination [deg], azimuth [deg]), the
    first at 0 m; the string's friction against the wall, static and dynamic (0: none); the
    ``formations`` along it, by increasing top (none: the preset's rock all the way)."""

    survey: tuple[tuple[float, float, float], ...] = ()
    friction_static: float = 0.0
    friction_dynamic: float = 0.0
    formations: tuple[Formation, ...] = ()

    def __post_init__(self) -> None:
        rows = []
        for i, row in enumerate(self.survey):
            if isinstance(row, (str, bytes)) or not hasattr(row, "__len__") or len(row) != 3:
                raise ParameterError(f"survey row {i} = {row!r}: expected [measured depth m, "
                                     "inclination deg, azimuth deg]")
            md = check_number(f"survey row {i} measured depth [m]", row[0], low_inclusive=True)
            inc = check_number(f"survey row {i} inclination [deg]", row[1], low_inclusive=True,
                               high=180.0)
            azi = check_number(f"survey row {i} azimuth [deg]", row[2], low=None)
            rows.append((md, inc, azi))
        if rows:
            if rows[0][0] != 0.0:
                raise ParameterError(f"survey row 0 at {rows[0][0]!r} m: expected the first row "
                                     "at measured depth 0 (the surface)")
            for i in range(1, len(rows)):
                if rows[i][0] <= rows[i - 1][0]:
                    raise ParameterError(f"survey row {i} at {rows[i][0]!r} m: expected measured "
                                         f"depths increasing (row {i - 1} is at "
                                         f"{rows[i - 1][0]!r} m)")
        object.__setattr__(self, "survey", tuple(rows))
        for name in ("friction_static", "friction_dynamic"):
            object.__setattr__(self, name, check_number(name, getattr(self, name),
                                                        low_inclusive=True, high=5.0))
        layers = []
        for i, f in enumerate(self.formations):
            if isinstance(f, dict):
                try:
                    f = Formation(**f)
                except TypeError as exc:
                    raise ParameterError(f"formations[{i}] = {f!r}: {exc}; expected top_m and "
                                         f"any of {', '.join(ROCK)}") from None
            if not isinstance(f, Formation):
                raise ParameterError(f"formations[{i}] = {f!r}: expected a mapping of top_m "
                                     f"[m] and any of {', '.join(ROCK)}")
            if layers and f.top_m <= layers[-1].top_m:
                raise ParameterError(f"formations[{i}] at {f.top_m:g} m: expected tops "
                                     f"increasing (formations[{i - 1}] is at "
                                     f"{layers[-1].top_m:g} m)")
            layers.append(f)
        object.__setattr__(self, "formations", tuple(layers))
        if self.friction_dynamic > self.friction_static:
            raise ParameterError(f"friction_dynamic = {self.friction_dynamic!r} is out of range: "
                                 f"expected <= friction_static = {self.friction_static!r}")

    @property
    def rubs(self) -> bool:
        """Whether the string rubs on the wall anywhere (a survey and friction)."""
        return bool(self.survey) and self.friction_static > 0.0

    def check_depth(self, depth_m: float) -> None:
        """A survey must reach the bit (``depth_m``)."""
        if self.survey and self.survey[-1][0] < depth_m * (1.0 - 1e-12):
            raise ParameterError(f"well.survey: its last row is at {self.survey[-1][0]:g} m, above "
                                 f"the bit at {depth_m:g} m measured depth; expected rows down "
                                 "to the bit")

    def tangent(self, md_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Unit tangent t (downhole) and curvature vector dt/ds [1/m] at each measured depth
        [m], shape (n, 3) each, axes (north, east, down)."""
        md = np.atleast_1d(np.asarray(md_m, dtype=float))
        if not self.survey:
            t = np.zeros((md.size, 3))
            t[:, 2] = 1.0
            return t, np.zeros((md.size, 3))
        rows = np.array(self.survey)
        ends = np.searchsorted(rows[:, 0], md, side="right").clip(1, len(rows) - 1)
        t, k = np.empty((md.size, 3)), np.empty((md.size, 3))
        for i, (e, s) in enumerate(zip(ends, md, strict=True)):
            (s0, i0, a0), (s1, i1, a1) = rows[e - 1], rows[e]
            t0, t1 = _unit(i0, a0), _unit(i1, a1)
            length = s1 - s0
            f = min(max((s - s0) / length, 0.0), 1.0) if length > 0 else 0.0
            beta = math.acos(min(1.0, max(-1.0, float(t0 @ t1))))
            if beta < 1e-12:
                t[i], k[i] = t0, 0.0
                continue
            sb = math.sin(beta)
            t[i] = (math.sin((1.0 - f) * beta) * t0 + math.sin(f * beta) * t1) / sb
            k[i] = (beta / length) * (-math.cos((1.0 - f) * beta) * t0
                                      + math.cos(f * beta) * t1) / sb
        return t, k


def _unit(inclination_deg: float, azimuth_deg: float) -> np.ndarray:
    i, a = math.radians(inclination_deg), math.radians(azimuth_deg)
    return np.array([math.sin(i) * math.cos(a), math.sin(i) * math.sin(a), math.cos(i)])


def along_hole(well: Well, tops_m: list[float], lengths_m: list[float],
               weights_n_m: list[float], points: int = 16) -> list[float]:
    """For consecutive sections (top measured depth, length [m], buoyed weight per unit
    length [N/m]), top first: each section's buoyed weight along the hole's axis, w
    integral(cos inclination) [N] (Gauss-Legendre, ``points`` on each piece between two survey
    rows, where the hole is one smooth arc)."""
    x, wq = np.polynomial.legendre.leggauss(points)
    rows = [r[0] for r in well.survey]
    axial = []
    for top, length, w in zip(tops_m, lengths_m, weights_n_m, strict=True):
        cuts = [top, *(md for md in rows if top < md < top + length), top + length]
        total = 0.0
        for a, b in itertools.pairwise(cuts):
            md = a + 0.5 * (b - a) * (x + 1.0)
            t, _ = well.tangent(md)
            total += 0.5 * (b - a) * float(np.sum(wq * t[:, 2]))
        axial.append(w * total)
    return axial


def normal_force(well: Well, md_m: float, tension_n: float, weight_n_m: float) -> float:
    """The soft string's wall force per unit length [N/m] at ``md_m``: |T dt/ds + w (g -
    (g.t) t)|, T the effective tension [N] there, w the buoyed weight per unit length [N/m]."""
    t, k = well.tangent(np.array([md_m]))
    t, k = t[0], k[0]
    g = np.array([0.0, 0.0, 1.0])
    return float(np.linalg.norm(tension_n * k + weight_n_m * (g - (g @ t) * t)))
