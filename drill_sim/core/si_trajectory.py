"""A run's sampled outputs in SI: what ``Trajectory.to_si`` returns.

Its own module so the dimensionless stepper stays free of unit conversions; the field names
carry the units and match the SI columns of ``drill_sim simulate``'s CSV.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .parameters import Scales

if TYPE_CHECKING:
    from .trajectory import Trajectory


@dataclass(frozen=True)
class SITrajectory:
    """Sampled outputs of a run in SI, one array per quantity. Axial quantities are positive
    downhole, as in ``RigSample``."""

    time_s: np.ndarray
    bit_speed_rad_s: np.ndarray
    rop_m_s: np.ndarray                # bit axial velocity
    wob_n: np.ndarray                  # weight on bit, stick reaction included
    tob_nm: np.ndarray                 # torque on bit
    surface_torque_nm: np.ndarray      # string torque, as the top drive measures it
    depth_of_cut_m: np.ndarray         # per revolution, d = n d_n (negative off bottom)
    bit_depth_m: np.ndarray            # bit position below its start
    bit_angle_rad: np.ndarray
    top_drive_speed_rad_s: np.ndarray  # the top drive's (kinematic mode: the command)
    available_weight_n: np.ndarray     # commanded, W0 = W_s - H0
    stuck: np.ndarray                  # bool
    off_bottom: np.ndarray             # bool
    top_drive_speed_setpoint_rad_s: np.ndarray  # the speed command
    motor_torque_nm: np.ndarray        # applied (kinematic mode: the string torque)

    @classmethod
    def of(cls, tr: Trajectory, scales: Scales, blade_count: int) -> SITrajectory:
        """Scale ``tr``'s dimensionless arrays; ``blade_count`` turns the depth of cut per blade
        into the depth per revolution."""
        c = scales.stiffness_nm_per_rad
        return cls(time_s=tr.tau * scales.time_s, bit_speed_rad_s=tr.omega / scales.time_s,
                   rop_m_s=tr.v * scales.velocity_m_s, wob_n=tr.w * scales.force_n,
                   tob_nm=tr.t * c, surface_torque_nm=tr.ts * c,
                   depth_of_cut_m=tr.delta_n * blade_count * scales.length_m,
                   bit_depth_m=tr.u * scales.length_m, bit_angle_rad=tr.phi.copy(),
                   top_drive_speed_rad_s=tr.omega_td / scales.time_s,
                   available_weight_n=tr.w0 * scales.force_n, stuck=tr.stuck.copy(),
                   off_bottom=tr.off_bottom.copy(),
                   top_drive_speed_setpoint_rad_s=tr.omega0 / scales.time_s,
                   motor_torque_nm=tr.motor_torque * c)
