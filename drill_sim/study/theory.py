"""Lines of the linear theory (msg_docs/model.md) to draw over a map, as fields whose zero
contour is the line; every function takes numpy arrays of the dimensionless groups and commands.

Axial mode. On s = i w, Delta(s) = (s^2 + 1)(s^2 + n psi E) - k s^2 E with E = 1 - exp(-s tau_n0)
vanishes off the torsional root only where E is real, E = 2 (w tau_n0 = pi, the first lobe):
w^4 - (1 + 2 n psi - 2 k) w^2 + 2 n psi = 0, k = n (w0 - lambda) / (2 pi). With the larger
root w_a and tau_n0 = 2 pi / (n omega0), the axial (regenerative) family crosses at
omega0 = 2 w_a / n: steady drilling's axial mode is unstable below it, stable above. For k -> 0 and
n psi >> 1 it tends to omega0 = 2 sqrt(2 psi / n), the threshold of the axial factor alone.
The torsional root near s = i stays weakly unstable everywhere (RGD), so it draws no line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class TheoryLine:
    """A line to draw: where ``field`` (on the plot's fine grid) crosses zero."""

    label: str
    style: str        # matplotlib line style
    color: str
    field: np.ndarray


def axial_threshold(n, psi):
    """omega0 = 2 sqrt(2 psi / n) [1/t*]: the axial factor's threshold (no coupling)."""
    return 2.0 * np.sqrt(2.0 * np.asarray(psi, dtype=float) / n)


def axial_neutral_speed(n, psi, lam, w0):
    """omega0 [1/t*] at which the axial family of Delta(s) crosses Re s = 0 (first lobe);
    NaN where there is no steady drilling (w0 <= lambda) or no crossing."""
    n, psi, lam, w0 = (np.asarray(a, dtype=float) for a in (n, psi, lam, w0))
    k = n * (w0 - lam) / (2.0 * math.pi)
    b = 1.0 + 2.0 * n * psi - 2.0 * k
    disc = b * b - 8.0 * n * psi
    with np.errstate(invalid="ignore"):
        x = 0.5 * (b + np.sqrt(disc))         # the larger root for w^2
        speed = 2.0 * np.sqrt(x) / n
    return np.where((w0 > lam) & (disc >= 0) & (b > 0), speed, np.nan)


def theory_lines(n, psi, lam, beta, w0, omega0) -> list[TheoryLine]:
    """The lines that cross the given grid of (dimensionless) points, each once: the axial
    neutral curve, its uncoupled threshold 2 sqrt(2 psi/n), the end of steady drilling
    (w0 = lambda, W0 = a l sigma) and beta = 1 (no stick-slip above)."""
    candidates = [
        TheoryLine("axial mode neutral (linear theory; stable to higher speed)", "-", "white",
                   omega0 - axial_neutral_speed(n, psi, lam, w0)),
        TheoryLine("ω0 = 2√(2ψ/n) (axial mode alone)", ":", "white",
                   omega0 - axial_threshold(n, psi)),
        TheoryLine("W0 = aℓσ (no steady drilling below)", "--", "orange",
                   np.asarray(w0 - lam, dtype=float)),
        TheoryLine("β = 1 (seed: stick-slip only below)", "-.", "orange",
                   np.asarray(beta - 1.0 + 0.0 * w0, dtype=float)),
    ]
    return [line for line in candidates if _crosses(line.field)]


def _crosses(field: np.ndarray) -> bool:
    finite = field[np.isfinite(field)]
    return finite.size > 0 and finite.min() < 0.0 < finite.max()
