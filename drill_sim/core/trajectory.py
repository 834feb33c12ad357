"""What the dimensionless stepper reports: ``StateView``, a copy of its state now,
``Trajectory``, a run's sampled outputs (``Simulator.state``, ``Simulator.run``), and
``SITrajectory``, the same samples in SI (``Trajectory.to_si``; field names carry the units
and match the SI columns of ``drill_sim simulate``'s CSV)."""

from __future__ import annotations

from dataclasses import dataclass, make_dataclass

import numpy as np

from . import kernel as kn
from . import state_layout as sl
from .metrics import Metrics
from .parameters import Scales


def _view_fields() -> tuple[tuple[str, int], ...]:
    """(name, index into x) of the state view's float slots, in the declaration's order."""
    return tuple((s.name, i) for i, s in enumerate(sl.STATE.of(sl.LUMPED)) if s.view)


VIEW_SLOTS = _view_fields()    # StateView's float fields: (name, index into the state x)


def _stuck(self) -> bool:
    return self.regime == kn.REGIME_STUCK


def _off_bottom(self) -> bool:
    return self.regime == kn.REGIME_OFF_BOTTOM


def _rescaled(self, old: Scales, new: Scales) -> StateView:
    """The same physical state at the ``new`` scales (each slot by its unit)."""
    return StateView(**{name: sl.STATE.slots[i].unit.rescale(getattr(self, name), old, new)
                        for name, i in VIEW_SLOTS}, regime=self.regime)


StateView = make_dataclass(
    "StateView", [(name, float) for name, _ in VIEW_SLOTS] + [("regime", int)], frozen=True,
    namespace={"stuck": property(_stuck), "off_bottom": property(_off_bottom),
               "rescaled": _rescaled, "__module__": __name__})
StateView.__doc__ = (
    "A copy of the instantaneous state, dimensionless, with the model contract's names: "
    "the lumped string's slots of ``state_layout.STATE`` (their units there) and the regime "
    "(kernel.REGIME_*). ``motor_torque`` in kinematic mode is the string torque ts, which "
    "imposes omega0.")


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
        return cls(tau=rows[:, sl.O_TAU].copy(), u=rows[:, sl.O_U].copy(),
                   v=rows[:, sl.O_V].copy(), phi=rows[:, sl.O_PHI].copy(),
                   omega=rows[:, sl.O_OMEGA].copy(), w=rows[:, sl.O_W].copy(),
                   t=rows[:, sl.O_T].copy(), ts=rows[:, sl.O_TS].copy(),
                   delta_n=rows[:, sl.O_DELTA].copy(),
                   stuck=rows[:, sl.O_REGIME] == kn.REGIME_STUCK,
                   off_bottom=rows[:, sl.O_REGIME] == kn.REGIME_OFF_BOTTOM,
                   w0=rows[:, sl.O_W0].copy(), omega0=rows[:, sl.O_OMEGA0].copy(),
                   metrics=metrics, omega_td=rows[:, sl.O_OMEGA_TD].copy(),
                   motor_torque=rows[:, sl.O_TM].copy())

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
