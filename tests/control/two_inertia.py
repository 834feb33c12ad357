"""A tiny two-inertia rig for closed-loop checks of the laws, independent of the core.

Top drive J_TD driven by the law's motor torque, a torsional spring C (the string), the BHA
inertia I with a constant friction torque. Semi-implicit Euler at a fine step, the law's
output held over each sample period (zero-order hold), as a drive applies it.
"""

from __future__ import annotations

import math

import numpy as np

from drill_sim.control import Law, SurfaceMeasurement


def run(law: Law, *, stiffness_nm_rad: float, bha_inertia_kg_m2: float,
        top_drive_inertia_kg_m2: float, friction_nm: float, speed_set_rad_s: float,
        bha_kick_rad_s: float, duration_s: float, substeps: int = 10,
        speed_noise_rad_s: float = 0.0, seed: int = 0,
        new_speed_set_rad_s: float | None = None) -> dict[str, np.ndarray]:
    """Start at steady rotation, kick the BHA's speed, return the time series per sample.

    The law takes over bumplessly from the friction torque at the first sample; a new
    set-point, if given, applies from the second.
    """
    rng = np.random.default_rng(seed)
    h = law.h_s
    dt = h / substeps
    c, inertia, j_td = stiffness_nm_rad, bha_inertia_kg_m2, top_drive_inertia_kg_m2
    twist = friction_nm / c
    speed_top = speed_set_rad_s
    speed_bha = speed_set_rad_s + bha_kick_rad_s
    law.reset(speed_set_rad_s)
    torque = friction_nm
    n = math.ceil(duration_s / h)
    out = {k: np.empty(n) for k in ("time_s", "top_speed", "bha_speed", "motor_torque")}
    for k in range(n):
        noise = rng.normal(0.0, speed_noise_rad_s) if speed_noise_rad_s else 0.0
        m = SurfaceMeasurement(k * h, speed_top + noise, torque, c * twist)
        if k == 0:
            torque = law.bumpless_start(friction_nm, m)
            if new_speed_set_rad_s is not None:
                law.set_speed(new_speed_set_rad_s)
        else:
            torque = law.step(m)
        out["time_s"][k], out["top_speed"][k] = k * h, speed_top
        out["bha_speed"][k], out["motor_torque"][k] = speed_bha, torque
        for _ in range(substeps):
            spring = c * twist
            speed_top += dt * (torque - spring) / j_td
            speed_bha += dt * (spring - friction_nm) / inertia
            twist += dt * (speed_top - speed_bha)
    return out


def decay_rate_1_s(time_s: np.ndarray, signal: np.ndarray) -> float:
    """Exponential decay rate [1/s] of an oscillation from a line through its log peak heights."""
    x = signal - signal[-len(signal) // 5:].mean()
    peaks = [i for i in range(1, len(x) - 1) if x[i] > x[i - 1] and x[i] >= x[i + 1]
             and x[i] > 0.0]
    heights = np.array([x[i] for i in peaks])
    keep = heights > 1e-3 * heights.max()
    slope = np.polyfit(time_s[peaks][keep], np.log(heights[keep]), 1)[0]
    return -slope
