"""Metrics (model contract, section 7) over a window, from the kernel's running integrals.

SSI (stick-slip severity index) = (omega_max - omega_min) / (2 omega_mean) of the bit speed over
the window: 0 for steady rotation, >= 1 whenever the bit stops. Means are time averages over
the window, the stick reaction counted in the weight and torque on bit.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from . import state_layout as sl
from .parameters import Scales
from .stick_slip import severity_index


@dataclass(frozen=True)
class Metrics:
    """Window metrics, dimensionless (angular speeds [1/t*], forces [F*], torques [C])."""

    duration: float
    ssi: float
    stick_fraction: float
    bounce_fraction: float
    mean_bit_speed: float
    min_bit_speed: float
    max_bit_speed: float
    mean_wob: float
    mean_tob: float
    mean_surface_torque: float
    mean_rop: float
    mean_w0: float
    mean_omega0: float             # the speed command (the set-point in speed mode)
    work_top_drive: float          # [C] (torque scale times rad), the string's torque at the top
    dissipated_rotation: float     # [C]
    work_weight: float             # [F* L*]
    work_hoist: float              # [F* L*]
    dissipated_axial: float        # [F* L*]
    # the top drive (kinematic mode: mean_omega0, the string's torque, work_top_drive); NaN
    # when built without them
    mean_top_drive_speed: float = math.nan
    mean_motor_torque: float = math.nan    # [C]
    work_motor: float = math.nan           # [C]

    @classmethod
    def from_accumulators(cls, acc: np.ndarray) -> Metrics:
        time = acc[sl.A_TIME]
        if time <= 0.0:
            nan = math.nan
            return cls(0.0, *([nan] * 20))
        mean_omega = acc[sl.A_OMEGA] / time
        return cls(
            duration=time,
            ssi=severity_index(acc[sl.A_OMEGA_MAX], acc[sl.A_OMEGA_MIN], mean_omega),
            stick_fraction=acc[sl.A_STICK_TIME] / time,
            bounce_fraction=acc[sl.A_BOUNCE_TIME] / time,
            mean_bit_speed=mean_omega,
            min_bit_speed=acc[sl.A_OMEGA_MIN],
            max_bit_speed=acc[sl.A_OMEGA_MAX],
            mean_wob=acc[sl.A_W] / time,
            mean_tob=acc[sl.A_T] / time,
            mean_surface_torque=acc[sl.A_TS] / time,
            mean_rop=acc[sl.A_V] / time,
            mean_w0=acc[sl.A_W0] / time,
            mean_omega0=acc[sl.A_OMEGA0] / time,
            work_top_drive=acc[sl.A_WORK_TOP_DRIVE],
            dissipated_rotation=acc[sl.A_DISSIPATED_ROT],
            work_weight=acc[sl.A_WORK_WEIGHT],
            work_hoist=acc[sl.A_WORK_HOIST],
            dissipated_axial=acc[sl.A_DISSIPATED_AX],
            mean_top_drive_speed=acc[sl.A_OMEGA_TD] / time,
            mean_motor_torque=acc[sl.A_TM] / time,
            work_motor=acc[sl.A_WORK_MOTOR],
        )

    def as_dict(self) -> dict[str, float]:
        return asdict(self)

    def to_si(self, scales: Scales) -> dict[str, float]:
        """The same metrics in SI, every key carrying its unit."""
        c, f, length = scales.stiffness_nm_per_rad, scales.force_n, scales.length_m
        w_rate = 1.0 / scales.time_s
        return {
            "duration_s": self.duration * scales.time_s,
            "ssi": self.ssi,
            "stick_fraction": self.stick_fraction,
            "bounce_fraction": self.bounce_fraction,
            "mean_bit_speed_rad_s": self.mean_bit_speed * w_rate,
            "min_bit_speed_rad_s": self.min_bit_speed * w_rate,
            "max_bit_speed_rad_s": self.max_bit_speed * w_rate,
            "mean_wob_n": self.mean_wob * f,
            "mean_tob_nm": self.mean_tob * c,
            "mean_surface_torque_nm": self.mean_surface_torque * c,
            "mean_rop_m_s": self.mean_rop * scales.velocity_m_s,
            "mean_available_weight_n": self.mean_w0 * f,
            "mean_top_drive_speed_rad_s": self.mean_top_drive_speed * w_rate,
            "mean_top_drive_speed_setpoint_rad_s": self.mean_omega0 * w_rate,
            "mean_motor_torque_nm": self.mean_motor_torque * c,
            "work_top_drive_j": self.work_top_drive * c,
            "dissipated_rotation_j": self.dissipated_rotation * c,
            "work_weight_j": self.work_weight * f * length,
            "work_hoist_j": self.work_hoist * f * length,
            "dissipated_axial_j": self.dissipated_axial * f * length,
            "work_motor_j": self.work_motor * c,
        }
