"""The top drive (model contract, section 9): its parameters in SI and dimensionless (its law
for one step is the kernel's ``_drive_step``).

J_TD dOmega_TD/dt = T_m - T_string, T_string = C (Phi_TD - Phi). The motor torque T_m is the
drive's output: a reference (``speed`` mode: the drive's PI on Omega_set - Omega_TD;
``torque`` mode: the command) limited in rate and to [T_min, T_max], then a first-order lag
(the drive's current loop). ``kinematic`` mode is the seed's ideal speed source, the default.

Defaults and their sources (msg_docs/model.md, "The top drive"): J_TD = 2900 kg m^2, 60 kN m
of motor torque and the "stiff" PI K_p = 50 Z, K_i = 5 J_TD [N m/rad] (Z = J_pipe sqrt(G rho),
the pipe's torsional impedance) are those of NORCE's open Simulator4nDOF (TopDriveDrawwork.cs,
TopdriveController.cs).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from .kernel import MODE_KINEMATIC, MODE_SPEED, MODE_TORQUE
from .parameters import ParameterError, Scales, check_number

MODES = ("kinematic", "speed", "torque")
_CODES = {"kinematic": MODE_KINEMATIC, "speed": MODE_SPEED, "torque": MODE_TORQUE}

DEFAULT_INERTIA_KG_M2 = 2900.0      # Simulator4nDOF's TopDriveInertia
DEFAULT_TORQUE_LIMIT_NM = 60e3      # Simulator4nDOF's MaximumTopDriveTorque
KP_PER_IMPEDANCE = 50.0             # K_p = 50 Z, Simulator4nDOF's stiff PI
KI_PER_INERTIA_S2 = 5.0             # K_i = 5 J_TD [1/s^2], likewise


def check_mode(mode: object) -> str:
    if mode not in MODES:
        raise ParameterError(f"top_drive_mode = {mode!r} is not a mode: expected one of "
                             f"{', '.join(MODES)}")
    return str(mode)


def _check_limits(t_min: float, t_max: float, unit: str) -> None:
    if not t_min < t_max:
        raise ParameterError(f"motor_torque_min{unit} = {t_min!r} is out of range: expected "
                             f"below motor_torque_max{unit} = {t_max!r}")


@dataclass(frozen=True)
class TopDriveParameters:
    """The top drive in SI. ``drive_kp_nm_s_rad`` None: 50 Z, known only from a string's
    geometry (a preset fills it in), so ``speed`` mode needs it; ``drive_ki_nm_rad`` None:
    5 J_TD. ``motor_torque_rate_nm_s`` math.inf (or None): no rate limit; ``drive_lag_s`` 0:
    no lag."""

    top_drive_mode: str = "kinematic"
    top_drive_inertia_kg_m2: float = DEFAULT_INERTIA_KG_M2
    motor_torque_max_nm: float = DEFAULT_TORQUE_LIMIT_NM
    motor_torque_min_nm: float = -DEFAULT_TORQUE_LIMIT_NM   # 0: a drive that cannot brake
    motor_torque_rate_nm_s: float = math.inf
    drive_lag_s: float = 0.0
    drive_kp_nm_s_rad: float | None = None
    drive_ki_nm_rad: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "top_drive_mode", check_mode(self.top_drive_mode))
        low = {"top_drive_inertia_kg_m2": (0.0, False), "motor_torque_max_nm": (0.0, True),
               "motor_torque_min_nm": (None, False), "motor_torque_rate_nm_s": (0.0, False),
               "drive_lag_s": (0.0, True), "drive_kp_nm_s_rad": (0.0, True),
               "drive_ki_nm_rad": (0.0, True)}
        if self.motor_torque_rate_nm_s is None:       # YAML null: no rate limit
            object.__setattr__(self, "motor_torque_rate_nm_s", math.inf)
        for f in fields(self)[1:]:
            value = getattr(self, f.name)
            if value is None or (f.name == "motor_torque_rate_nm_s" and value == math.inf):
                continue
            bound, inclusive = low[f.name]
            high = 0.0 if f.name == "motor_torque_min_nm" else None
            object.__setattr__(self, f.name, check_number(f.name, value, low=bound,
                                                          low_inclusive=inclusive, high=high))
        _check_limits(self.motor_torque_min_nm, self.motor_torque_max_nm, "_nm")
        if self.drive_ki_nm_rad is None:
            object.__setattr__(self, "drive_ki_nm_rad",
                               KI_PER_INERTIA_S2 * self.top_drive_inertia_kg_m2)
        if self.top_drive_mode == "speed" and self.drive_kp_nm_s_rad is None:
            raise ParameterError("drive_kp_nm_s_rad = None: speed mode needs the drive's "
                                 "proportional gain [N m s/rad] (default 50 Z, from a "
                                 "preset's string geometry)")

    def as_dict(self) -> dict[str, object]:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    def groups(self, scales: Scales, bha_inertia_kg_m2: float) -> DriveGroups:
        """The dimensionless drive: inertia by I, torques by C, time by t*."""
        c, ts = scales.stiffness_nm_per_rad, scales.time_s
        kp = 0.0 if self.drive_kp_nm_s_rad is None else self.drive_kp_nm_s_rad
        return DriveGroups(
            mode=self.top_drive_mode, j=self.top_drive_inertia_kg_m2 / bha_inertia_kg_m2,
            t_max=self.motor_torque_max_nm / c, t_min=self.motor_torque_min_nm / c,
            rate=self.motor_torque_rate_nm_s * ts / c, lag=self.drive_lag_s / ts,
            kp=kp / (c * ts), ki=self.drive_ki_nm_rad / c)


@dataclass(frozen=True)
class DriveGroups:
    """The top drive, dimensionless: j = J_TD/I; motor torque limits t_min, t_max [C]; rate
    limit [C/t*] (math.inf: none); lag [t*] (0: none); PI gains kp [C t*], ki [C]."""

    mode: str = "kinematic"
    j: float = 1.0
    t_max: float = math.inf
    t_min: float = -math.inf
    rate: float = math.inf
    lag: float = 0.0
    kp: float = 0.0
    ki: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "mode", check_mode(self.mode))
        object.__setattr__(self, "j", check_number("j (J_TD/I)", self.j))
        for name, low, inclusive in (("t_max", 0.0, True), ("t_min", None, False),
                                     ("rate", 0.0, False)):
            value = getattr(self, name)
            if value != (-math.inf if name == "t_min" else math.inf):
                object.__setattr__(self, name, check_number(
                    name, value, low=low, low_inclusive=inclusive,
                    high=0.0 if name == "t_min" else None))
        _check_limits(self.t_min, self.t_max, "")
        for name in ("lag", "kp", "ki"):
            object.__setattr__(self, name, check_number(name, getattr(self, name),
                                                        low_inclusive=True))

    def holds(self, torque: float) -> bool:
        """Whether the drive can hold the string's top torque ``torque`` [C] (a steady start's):
        any torque in kinematic mode, else one within [t_min, t_max]."""
        return self.mode == "kinematic" or self.t_min <= torque <= self.t_max

    @property
    def code(self) -> int:
        return _CODES[self.mode]

    def fastest_frequency(self) -> float:
        """[1/t*] of the drive's fastest mode: the two inertias on the string,
        sqrt(1 + 1/j), and in speed mode the PI's integral loop, sqrt(ki/j)."""
        if self.mode == "kinematic":
            return 1.0
        freq = math.sqrt(1.0 + 1.0 / self.j)
        return max(freq, math.sqrt(self.ki / self.j)) if self.mode == "speed" else freq

    def lag_weights(self, h: float) -> tuple[float, float]:
        """(end, mean): over a step h with the reference r held, the lagged torque moves from
        T to T + end (r - T) and averages T + mean (r - T) (the lag solved exactly)."""
        if self.lag == 0.0:
            return 1.0, 1.0
        x = h / self.lag
        return -math.expm1(-x), 1.0 + math.expm1(-x) / x
