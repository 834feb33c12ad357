"""The SI arithmetic of a rig's control period, compiled once: its surface commands into the
kernel's arrays, the sample's force sums and its outputs in SI out of them.

``Rig`` (``command``, ``sample``), ``Simulator.take_force_sums`` and the vector environment's
step (``gym.vector_step``) all call these, so a rig stepped alone and a row of the vector
environment compute every number the same way. ``scales`` is a row of ``SCALE_FIELDS``
(``scale_row``); a sample is a row of ``SAMPLE_FIELDS``, the float fields of ``RigSample``
that the state gives (the mean forces and the hook load come from elsewhere).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from . import state_layout
from .numba_cache import follow
from .parameters import RigParameters
from .state_layout import (
    A_T,
    A_W,
    C_OMEGA0,
    C_T_CMD,
    C_W0,
    K_REGIME,
    K_SAMPLED,
    K_STEPS,
    X_DELTA,
    X_HOLE,
    X_OMEGA,
    X_OMEGA_TD,
    X_PHI,
    X_PHI_TD,
    X_SUM_T,
    X_SUM_W,
    X_TM,
    X_TS,
    X_U,
    X_V,
)

follow(__file__, state_layout.__file__)      # the cache follows the layout it compiles

# a rig's scales, SI: t* [s], F* [N], C [N m/rad], L* [m], the submerged weight W_s [N], the
# step [s], L*/t* [m/s], the blade count n
SCALE_FIELDS = ("time_s", "force_n", "torque_nm", "length_m", "submerged_weight_n", "dt_s",
                "velocity_m_s", "blade_count")
(S_TIME, S_FORCE, S_TORQUE, S_LENGTH, S_WEIGHT, S_DT, S_VELOCITY, S_BLADES) = range(8)

# a sample's fields the state gives, in ``RigSample``'s names and units
SAMPLE_FIELDS = ("time_s", "bit_speed_rad_s", "rop_m_s", "surface_torque_nm", "depth_of_cut_m",
                 "bit_depth_m", "hole_depth_m", "bit_angle_rad", "top_drive_angle_rad",
                 "top_drive_speed_rad_s", "motor_torque_nm", "regime")
(R_TIME, R_BIT, R_ROP, R_SURFACE, R_CUT, R_DEPTH, R_HOLE, R_ANGLE, R_TD_ANGLE, R_TD_SPEED,
 R_MOTOR, R_REGIME) = range(12)
NR = len(SAMPLE_FIELDS)


def scale_row(params: RigParameters, dt_s: float) -> np.ndarray:
    """``params``' scales as the row ``SCALE_FIELDS``, for a step of ``dt_s`` [s]."""
    sc = params.scales
    return np.array([sc.time_s, sc.force_n, sc.stiffness_nm_per_rad, sc.length_m,
                     params.submerged_weight_n, dt_s, sc.velocity_m_s, params.blade_count],
                    dtype=np.float64)


@njit(cache=True, inline="always")
def surface_commands(speed_rad_s, hook_load_n, scales):
    """The kernel's commands (w0 [F*], omega0 [1/t*]) of a top-drive speed [rad/s] and a hook
    load [N]: w0 = (W_s - H0)/F*, omega0 = Omega0 t*."""
    return ((scales[S_WEIGHT] - hook_load_n) / scales[S_FORCE], speed_rad_s * scales[S_TIME])


@njit(cache=True, inline="always")
def write_commands(x, c, kinematic, speed_rad_s, hook_load_n, scales):
    """Hold these surface commands (``surface_commands``) in ``c``; the kinematic drive turns
    at the speed command at once."""
    w0, om0 = surface_commands(speed_rad_s, hook_load_n, scales)
    c[C_W0] = w0
    c[C_OMEGA0] = om0
    if kinematic:
        x[X_OMEGA_TD] = om0


@njit(cache=True, inline="always")
def write_motor_torque(c, torque_nm, scales):
    """Hold this motor torque command [N m] in ``c`` (torque mode), in C."""
    c[C_T_CMD] = torque_nm / scales[S_TORQUE]


@njit(cache=True, inline="always")
def take_force_sums(x, k, acc, h):
    """(sum of w, sum of t, steps) over the steps since the previous sample, and start the
    next: the window's integrals take the sample in (``h`` the step [t*])."""
    sum_w, sum_t = x[X_SUM_W], x[X_SUM_T]
    n = k[K_STEPS] - k[K_SAMPLED]
    acc[A_W] += h * sum_w
    acc[A_T] += h * sum_t
    x[X_SUM_W] = 0.0
    x[X_SUM_T] = 0.0
    k[K_SAMPLED] = k[K_STEPS]
    return sum_w, sum_t, n


@njit(cache=True, inline="always")
def mean_forces(sum_w, sum_t, n, pending_w_n, pending_t_nm, scales):
    """(WOB [N], TOB [N m]) averaged over ``n`` steps (``n`` counting any pending ones) from
    the sums [F*], [C] and what is pending in SI (steps before a change of scales)."""
    return ((pending_w_n + sum_w * scales[S_FORCE]) / n,
            (pending_t_nm + sum_t * scales[S_TORQUE]) / n)


@njit(cache=True, inline="always")
def sample_into(x, k, kinematic, speed_cmd_rad_s, scales, out):
    """The sample's fields the state gives (``SAMPLE_FIELDS``, SI) into ``out``: the values
    now. The kinematic drive's speed is the command and its motor torque the string's."""
    ts, cn = scales[S_TIME], scales[S_TORQUE]
    out[R_TIME] = k[K_STEPS] * scales[S_DT]
    out[R_BIT] = x[X_OMEGA] / ts
    out[R_ROP] = x[X_V] * scales[S_VELOCITY]
    out[R_SURFACE] = x[X_TS] * cn
    out[R_CUT] = scales[S_BLADES] * x[X_DELTA] * scales[S_LENGTH]
    out[R_DEPTH] = x[X_U] * scales[S_LENGTH]
    out[R_HOLE] = max(0.0, x[X_HOLE]) * scales[S_LENGTH]
    out[R_ANGLE] = x[X_PHI]
    out[R_TD_ANGLE] = x[X_PHI_TD]
    if kinematic:
        out[R_TD_SPEED] = speed_cmd_rad_s
        out[R_MOTOR] = x[X_TS] * cn
    else:
        out[R_TD_SPEED] = x[X_OMEGA_TD] / ts
        out[R_MOTOR] = x[X_TM] * cn
    out[R_REGIME] = k[K_REGIME]
