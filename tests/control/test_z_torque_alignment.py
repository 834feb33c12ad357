"""Z-Torque's pipe-torque estimate T̂_p = LPF_T(T_m - J_TD dΩ/dt) against a top drive computed
here, independently of the core and of the law: a free inertia J_TD driven by a motor torque
u (held over each 1 ms sample) against a known pipe torque T_p(t), integrated exactly.

The estimate is a difference of two large signals fed back with a gain α K_p/Z ≈ 140, so what
matters is that T_m cancels: the residual T̂_p - LPF_T(T_p) must not carry u. Three ways the
drive's signals reach the law: exact every sample, 100 Hz staircases (a drive's signals read
at 1 kHz), and 100 Hz with the torque signal filtered (τ 5 ms, as ``surface_rig``). Each time
the law told what the signals are cancels u; the law that assumes exact signals does not, and
in a closed loop that residual alone drives the motor torque to its limits.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from drill_sim.control import SurfaceMeasurement, make_law

H = 1e-3                      # the law's sample period [s]
J_TD = 2900.0
Z = 302.376
SPEED = 2 * math.pi
PIPE_MEAN, PIPE_AMP, PIPE_HZ = 8000.0, 3000.0, 0.7       # T_p(t) [N·m]
MOTOR_AMP, MOTOR_HZ = 20000.0, 3.0                       # the motor torque u's swing


def _pipe(t: np.ndarray) -> np.ndarray:
    return PIPE_MEAN + PIPE_AMP * np.sin(2 * math.pi * PIPE_HZ * t)


def _drive(n: int, motor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Top-drive speed at t_k = k h, and the motor torque applied over [t_k-1, t_k] (what a
    drive reports at t_k); u_k held over [t_k, t_k+1]; T_p's integral in closed form."""
    w = 2 * math.pi * PIPE_HZ
    t = np.arange(n + 1) * H
    pipe_integral = PIPE_MEAN * t + PIPE_AMP * (1 - np.cos(w * t)) / w
    speed = SPEED + (np.concatenate(([0.0], np.cumsum(motor[:n]) * H)) - pipe_integral) / J_TD
    applied = np.concatenate(([motor[0]], motor[:n]))
    return speed, applied


def _sensor(x: np.ndarray, every: int, tau_s: float) -> np.ndarray:
    """A first-order filter (exact for a held input), then a sample every ``every`` ticks
    held in between: a drive's signal as a 1 kHz law reads it."""
    y = np.empty_like(x)
    y[0] = x[0]
    decay = math.exp(-H / tau_s) if tau_s > 0 else 0.0
    for k in range(1, x.size):
        y[k] = x[k - 1] + (y[k - 1] - x[k - 1]) * decay if tau_s > 0 else x[k]
    held = y.copy()
    for k in range(x.size):
        held[k] = y[(k // every) * every]
    return held


def _residual(every: int, tau_s: float, gains: dict) -> float:
    """Largest |T̂_p - LPF_T(T_p)| over the last 4 s of an 8 s run (open loop: the law's output
    is not applied, so the motor torque is the same in every run)."""
    n = 8000
    t = np.arange(n + 1) * H
    motor = PIPE_MEAN + MOTOR_AMP * np.sin(2 * math.pi * MOTOR_HZ * t)
    speed, applied = _drive(n, motor)
    speed_m, torque_m = _sensor(speed, every, 0.0), _sensor(applied, every, tau_s)
    law = make_law("z_torque", H, Z, J_TD, **gains)
    law.reset(SPEED)
    estimate = np.empty(n + 1)
    law.bumpless_start(PIPE_MEAN, SurfaceMeasurement(0.0, speed_m[0], torque_m[0], 0.0))
    for k in range(n + 1):
        law.step(SurfaceMeasurement(t[k], speed_m[k], torque_m[k], 0.0))
        estimate[k] = law.pipe_torque_estimate_nm
    # the pipe torque through LPF_T (first order at its corner), in steady state, and the
    # delays of the signals' chain: the staircase's half period, the law's mean over the
    # period (another half), the filter τ
    wc = 2 * math.pi * law.lowpass_torque.corner_hz
    w = 2 * math.pi * PIPE_HZ
    lag = math.atan(w / wc) + w * ((every - 1) * H + tau_s)
    expected = PIPE_MEAN + PIPE_AMP / math.hypot(1, w / wc) * np.sin(w * t - lag)
    tail = t > 4.0
    return float(np.abs(estimate - expected)[tail].max())


@pytest.mark.parametrize(("every", "tau_s", "gains"), [
    (1, 0.0, {}),
    (10, 0.0, {"measurement_period_s": 0.01}),
    (10, 0.005, {"measurement_period_s": 0.01, "torque_signal_tau_s": 0.005}),
])
def test_the_estimate_cancels_the_motor_torque_when_told_the_signals(every, tau_s, gains):
    """The 20 kN·m swing of u leaves under 60 N·m (0.3 %) in T̂_p (with
    the bilinear derivative, half a sample off, 120 N·m at 1 kHz)."""
    assert _residual(every, tau_s, gains) < 60.0


@pytest.mark.parametrize(("every", "tau_s"), [(10, 0.0), (10, 0.005)])
def test_a_law_that_takes_staircases_for_exact_signals_keeps_part_of_the_motor_torque(every,
                                                                                     tau_s):
    """Told nothing, the law differences a 100 Hz staircase as if every sample were new and
    misses the torque filter: kN·m of u stay in the estimate."""
    assert _residual(every, tau_s, {}) > 1000.0


def _closed_loop_peak(gains: dict) -> float:
    """Free top drive (T_p = 0), 100 Hz signals with a 5 ms torque filter, the reference
    Z-Torque gains (K_p = 275 Z, α = 0.5), a 0.1 rad/s speed kick: the largest |T_m| over the
    last 5 s of 10 (limits ±60 kN·m)."""
    law = make_law("z_torque", H, Z, J_TD, alpha=0.5, kp_nm_s_rad=275 * Z,
                   torque_min_nm=-60e3, torque_max_nm=60e3, **gains)
    law.reset(SPEED)
    speed, torque = SPEED + 0.1, 0.0
    law.bumpless_start(0.0, SurfaceMeasurement(0.0, speed, 0.0, 0.0))
    sensed = (speed, torque)
    filtered = torque
    peak = 0.0
    for k in range(1, 10_001):
        speed += torque * H / J_TD
        filtered = torque + (filtered - torque) * math.exp(-H / 0.005)
        if k % 10 == 0:
            sensed = (speed, filtered)
        torque = law.step(SurfaceMeasurement(k * H, sensed[0], sensed[1], 0.0))
        if k > 5000:
            peak = max(peak, abs(torque))
    return peak


def test_told_the_signals_the_stiff_z_torque_loop_settles():
    assert _closed_loop_peak({"measurement_period_s": 0.01, "torque_signal_tau_s": 0.005}) < 600.0


def test_told_nothing_the_stiff_z_torque_loop_runs_onto_its_limits():
    assert _closed_loop_peak({}) == pytest.approx(60e3)
