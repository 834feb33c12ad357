"""The zeros of an analytic function in a box (x0, x1, y0, y1) of the complex plane (s in the
caller's unit, 1/t* in the stability modules): counted by the argument principle
(``winding_number``) and found by Newton's method from a grid (``newton_from_grid``)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .parameters import ParameterError

# s -> (f(s), f'(s)), elementwise on an array of s
ValueAndDerivative = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]
# (s, f(s), f'(s)) -> which s are zeros of f
IsZero = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def winding_number(box, f: Callable[[np.ndarray], np.ndarray], edge: str,
                   max_points: int = 2**21) -> int:
    """Zeros of the analytic ``f`` inside ``box`` = (x0, x1, y0, y1) by the argument principle,
    the edge refined until the phase moves less than pi/4 a point (or ``max_points`` a side);
    a zero on the edge is a ParameterError ending with ``edge`` (what to change)."""
    x0, x1, y0, y1 = box
    corners = [complex(x0, y0), complex(x1, y0), complex(x1, y1), complex(x0, y1), complex(x0, y0)]
    points = 2048
    while True:
        path = np.concatenate([np.linspace(corners[i], corners[i + 1], points, endpoint=False)
                               for i in range(4)] + [np.array([corners[0]])])
        value = f(path)
        if np.any(np.abs(value) == 0.0):
            raise ParameterError(f"a root lies on the search box edge; {edge}")
        steps = np.diff(np.unwrap(np.angle(value)))
        if np.max(np.abs(steps)) < math.pi / 4 or points > max_points:
            return round(np.sum(steps) / (2.0 * math.pi))
        points *= 4


def central_difference(f: Callable[[np.ndarray], np.ndarray], d: float = 1e-6
                       ) -> ValueAndDerivative:
    """s -> (f(s), (f(s + d) - f(s - d)) / 2d): ``f`` with its derivative by central difference."""
    def value_and_derivative(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return f(s), (f(s + d) - f(s - d)) / (2.0 * d)
    return value_and_derivative


def newton_from_grid(box, f: ValueAndDerivative, columns: int, rows: int,
                     is_zero: IsZero) -> np.ndarray:
    """The distinct zeros of ``f`` in ``box`` = (x0, x1, y0, y1) reached by 60 Newton steps
    from each point of a ``columns`` x ``rows`` grid over it (edges included; ``f`` gives value
    and derivative). An iterate farther than 4 max(|x0|, x1, y1) from 0 is dropped; a final one
    is a zero where it lies in the box and ``is_zero`` says so; two within 1e-6 (1 + |s|) of
    each other are one."""
    x0, x1, y0, y1 = box
    s = (np.linspace(x0, x1, columns)[None, :] + 1j * np.linspace(y0, y1, rows)[:, None]).ravel()
    with np.errstate(all="ignore"):            # iterates that leave the box become NaN
        for _ in range(60):
            value, deriv = f(s)
            step = value / deriv
            step[~np.isfinite(step)] = 0.0
            s = s - step
            s = np.where(np.abs(s) > 4.0 * max(abs(x0), x1, y1), np.nan, s)
        value, deriv = f(s)
    good = np.isfinite(s) & is_zero(s, value, deriv)
    good &= (s.real >= x0) & (s.real <= x1) & (s.imag >= y0) & (s.imag <= y1)
    found: list[complex] = []
    for root in s[good]:
        if all(abs(root - other) > 1e-6 * (1.0 + abs(root)) for other in found):
            found.append(complex(root))
    return np.array(found, dtype=complex)
