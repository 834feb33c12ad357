"""What the dimensionless stepper reports: ``StateView``, a copy of its state now,
``Trajectory``, a run's sampled outputs (``Simulator.state``, ``Simulator.run``), and
``SITrajectory``, the same samples in SI (``Trajectory.to_si``; field names carry the units
and match the SI columns of ``drill_sim simulate``'s CSV)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import kernel as kn
from .metrics import Metrics
from .parameters import Scales


@dataclass(frozen=True)
class StateView:
    """A copy of the instantaneous state, dimensionless, with the model contract's names."""

    tau: float
    u: float
    v: float
    phi: float
    omega: float
    phi_td: float
    w: float          # weight on bit over the last step (stick reaction included)
    t: float          # torque on bit over the last step (a stick's reaction included)
    ts: float         # string (surface) torque phi_td - phi
    delta_n: float    # depth of cut per blade
    g: float          # wear-flat contact factor
    regime: int       # kernel.REGIME_*
    since_stick: float
    omega_td: float = 0.0        # top-drive speed (kinematic mode: omega0)
    motor_torque: float = 0.0    # applied motor torque (kinematic mode: ts, which imposes omega0)
    drive_integral: float = 0.0  # the speed PI's integral term
    drive_reference: float = 0.0  # the drive's limited reference, the lag's input

    @property
    def stuck(self) -> bool:
        return self.regime == kn.REGIME_STUCK

    @property
    def off_bottom(self) -> bool:
        return self.regime == kn.REGIME_OFF_BOTTOM


@dataclass(frozen=True)
class Trajectory:
    """Sampled outputs of a run (dimensionless), one array per quantity of the model contract.

    w and t are means over each row's output interval (impulses of sticks and landings spread
    over the interval, as a sensor would see them); everything else is the value at the row.
    """

    tau: np.ndarray
    u: np.ndarray
    v: np.ndarray
    phi: np.ndarray
    omega: np.ndarray
    w: np.ndarray
    t: np.ndarray
    ts: np.ndarray
    delta_n: np.ndarray
    stuck: np.ndarray
    off_bottom: np.ndarray
    w0: np.ndarray
    omega0: np.ndarray       # the speed command: the set-point in speed mode
    metrics: Metrics
    omega_td: np.ndarray     # the top drive's speed (kinematic mode: omega0)
    motor_torque: np.ndarray  # applied motor torque (kinematic mode: ts, imposing omega0)

    @classmethod
    def from_rows(cls, rows: np.ndarray, metrics: Metrics) -> Trajectory:
        return cls(tau=rows[:, kn.O_TAU].copy(), u=rows[:, kn.O_U].copy(),
                   v=rows[:, kn.O_V].copy(), phi=rows[:, kn.O_PHI].copy(),
                   omega=rows[:, kn.O_OMEGA].copy(), w=rows[:, kn.O_W].copy(),
                   t=rows[:, kn.O_T].copy(), ts=rows[:, kn.O_TS].copy(),
                   delta_n=rows[:, kn.O_DELTA].copy(),
                   stuck=rows[:, kn.O_REGIME] == kn.REGIME_STUCK,
                   off_bottom=rows[:, kn.O_REGIME] == kn.REGIME_OFF_BOTTOM,
                   w0=rows[:, kn.O_W0].copy(), omega0=rows[:, kn.O_OMEGA0].copy(),
                   metrics=metrics, omega_td=rows[:, kn.O_OMEGA_TD].copy(),
                   motor_torque=rows[:, kn.O_TM].copy())

    def to_si(self, scales: Scales, blade_count: int) -> SITrajectory:
        """The same samples in SI, units in the field names (depth of cut per revolution)."""
        return SITrajectory.of(self, scales, blade_count)


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
