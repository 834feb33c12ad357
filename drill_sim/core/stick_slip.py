"""What stick-slip is, judged on a record of the bit (MODEL.md section 7): one definition for
every place that judges a run — the kernels' window metrics, the downhole severity channel,
a bag's metrics, the controller evaluation and the session's regime.

It imports nothing of the package (nor numpy), so the bag layer reads it without loading the
model's kernels, and the numba kernels compile these very functions.
"""

from __future__ import annotations

import math
from typing import Any


def severity_index(speed_max: float, speed_min: float, speed_mean: float) -> float:
    """SSI = (max - min) / (2 mean) of the bit speed over a window (any one unit): 0 for steady
    rotation, >= 1 whenever the bit stops; infinite when the mean speed is not positive."""
    if speed_mean > 0.0:
        return (speed_max - speed_min) / (2.0 * speed_mean)
    return math.inf


def stuck(bit_speed: Any, wob: Any) -> Any:
    """The bit is stuck where it does not rotate while pressed on the rock (speed exactly 0: the
    model's stick phase is exact, never a small speed); floats or numpy arrays alike."""
    return (bit_speed == 0.0) & (wob > 0.0)
