"""Reference stick-slip control laws on surface measurements, stepped at a fixed period h.

Every law maps a ``SurfaceMeasurement`` and a speed set-point Ω_set [rad/s] to the top drive's
command: a motor torque [N·m] (``output_kind == "torque"``) or, for a kinematic top drive, a
speed [rad/s] (``"speed"``). Plain Python floats in ``__slots__``: a step allocates nothing
beyond its result, which is cheap enough at 1 kHz.

Common to the torque laws: output limits [torque_min_nm, torque_max_nm]; anti-windup by
conditional integration (while the output is saturated in the direction the error pushes,
the integral grows no further than to put the output on the limit) plus clamping of the
integral term itself to the limits, so the output leaves a limit on the first sample after
the error changes sign; and bumpless start: ``bumpless_start(current_output, measurement)``
loads the integral so that its first output equals the torque the drive is applying now.
"""

from __future__ import annotations

from typing import ClassVar, NamedTuple

from ..core.parameters import ParameterError, check_number
from .filters import FilteredDerivative
from .tuning import tune_soft_speed

DEFAULT_TORQUE_LIMIT_NM = 1.0e5   # symmetric default limits; set them to the drive's rating


class SurfaceMeasurement(NamedTuple):
    """What a controller on the rig floor can measure, SI."""

    time_s: float
    top_drive_speed_rad_s: float   # Ω_TD
    motor_torque_nm: float         # T_m, as applied by the drive
    surface_torque_nm: float       # torque in the string just below the top drive


def check_limits(torque_min_nm: object, torque_max_nm: object) -> tuple[float, float]:
    """Finite output limits with min < max."""
    low = check_number("torque_min_nm", torque_min_nm, low=None)
    high = check_number("torque_max_nm", torque_max_nm, low=None)
    if not low < high:
        raise ParameterError(f"torque_max_nm = {high!r} is out of range: expected a finite "
                             f"number > torque_min_nm = {low!r}")
    return low, high


class PI:
    """T = K_p e + q, q = K_i ∫e dt (rectangle rule, this sample included), limited.

    The integral is kept in torque units (q, N·m), so a bumpless start just sets q.
    """

    __slots__ = ("h_s", "ki_nm_rad", "kp_nm_s_rad", "q_nm", "torque_max_nm", "torque_min_nm")

    def __init__(self, h_s: float, kp_nm_s_rad: float, ki_nm_rad: float,
                 torque_min_nm: float, torque_max_nm: float) -> None:
        self.h_s = h_s
        self.kp_nm_s_rad = check_number("kp_nm_s_rad", kp_nm_s_rad, low_inclusive=True)
        self.ki_nm_rad = check_number("ki_nm_rad", ki_nm_rad, low_inclusive=True)
        self.torque_min_nm, self.torque_max_nm = check_limits(torque_min_nm, torque_max_nm)
        self.q_nm = 0.0

    def load(self, output_nm: float, error_rad_s: float) -> None:
        """Set q so that ``output(error)`` (no feed-forward: the laws settle theirs to 0 when
        they take over) returns ``output_nm`` (if within limits)."""
        gain = self.kp_nm_s_rad + self.ki_nm_rad * self.h_s
        q = output_nm - gain * error_rad_s
        self.q_nm = min(max(q, self.torque_min_nm), self.torque_max_nm)

    def output(self, error_rad_s: float, feedforward_nm: float = 0.0) -> float:
        p = self.kp_nm_s_rad * error_rad_s + feedforward_nm
        q = self.q_nm + self.ki_nm_rad * self.h_s * error_rad_s
        # Conditional integration: while the error pushes into a limit, q grows only up to
        # what brings the output onto the limit, never beyond (no wind-up).
        if p + q > self.torque_max_nm and error_rad_s > 0.0:
            q = max(self.q_nm, self.torque_max_nm - p)
        elif p + q < self.torque_min_nm and error_rad_s < 0.0:
            q = min(self.q_nm, self.torque_min_nm - p)
        q = min(max(q, self.torque_min_nm), self.torque_max_nm)
        self.q_nm = q
        return min(max(p + q, self.torque_min_nm), self.torque_max_nm)


class Law:
    """Base: the set-point, the sample period and the interface every law keeps."""

    __slots__ = ("h_s", "impedance_nm_s_rad", "speed_set_rad_s", "top_drive_inertia_kg_m2")
    name: ClassVar[str] = ""
    # what the law commands, and so the drive it runs on and the rig topic it publishes to
    output_kind: ClassVar[str] = "torque"
    top_drive_mode: ClassVar[str] = "torque"
    command_topic: ClassVar[str] = "~/cmd/top_drive_torque"
    limited_by_drive: ClassVar[bool] = True       # its torque limits default to the drive's
    GAINS: ClassVar[tuple[str, ...]] = ()

    def __init__(self, h_s: float, impedance_nm_s_rad: float,
                 top_drive_inertia_kg_m2: float) -> None:
        self.h_s = check_number("h_s", h_s, high=1.0)
        self.impedance_nm_s_rad = check_number("impedance_nm_s_rad", impedance_nm_s_rad)
        self.top_drive_inertia_kg_m2 = check_number("top_drive_inertia_kg_m2",
                                                    top_drive_inertia_kg_m2)
        self.speed_set_rad_s = 0.0

    def set_speed(self, speed_set_rad_s: float) -> None:
        """Change Ω_set [rad/s]; takes effect on the next step."""
        self.speed_set_rad_s = check_number("speed_set_rad_s", speed_set_rad_s, low=None)

    def reset(self, speed_set_rad_s: float) -> None:
        """Forget all state (integral, filters) and set Ω_set."""
        self.set_speed(speed_set_rad_s)

    def step(self, measurement: SurfaceMeasurement) -> float:
        raise NotImplementedError

    def bumpless_start(self, current_output: float, measurement: SurfaceMeasurement) -> float:
        """Take over from a drive now applying ``current_output``; returns the first output."""
        raise NotImplementedError


class Kinematic(Law):
    """Pass-through for a kinematic top drive: outputs Ω_set [rad/s] as the speed command."""

    __slots__ = ()
    name = "kinematic"
    output_kind = "speed"
    top_drive_mode = "kinematic"
    command_topic = "~/cmd/top_drive"
    limited_by_drive = False

    def step(self, measurement: SurfaceMeasurement) -> float:
        return self.speed_set_rad_s

    def bumpless_start(self, current_output: float, measurement: SurfaceMeasurement) -> float:
        """Stateless, so bumpless means adopting the current speed command as Ω_set."""
        self.set_speed(current_output)
        return self.speed_set_rad_s


class Off(Law):
    """No control: holds the motor torque it was handed (0 N·m after reset), the open loop."""

    __slots__ = ("torque_nm",)
    name = "off"
    limited_by_drive = False

    def __init__(self, h_s: float, impedance_nm_s_rad: float,
                 top_drive_inertia_kg_m2: float) -> None:
        super().__init__(h_s, impedance_nm_s_rad, top_drive_inertia_kg_m2)
        self.torque_nm = 0.0

    def reset(self, speed_set_rad_s: float) -> None:
        super().reset(speed_set_rad_s)
        self.torque_nm = 0.0

    def step(self, measurement: SurfaceMeasurement) -> float:
        return self.torque_nm

    def bumpless_start(self, current_output: float, measurement: SurfaceMeasurement) -> float:
        self.torque_nm = check_number("current_output", current_output, low=None)
        return self.torque_nm


class StiffPI(Law):
    """The drive's own stiff speed loop: T_m = K_p e + K_i ∫e, e = Ω_set - Ω_TD.

    Defaults K_p = 50 Z [N·m·s/rad], K_i = 5 s⁻² · J_TD [N·m/rad] (the stiff drive of the NORCE
    Simulator4nDOF). Stiff means |top impedance| ≫ Z: waves from the bit reflect almost fully,
    which is why a stiff drive lets stick-slip live.
    """

    __slots__ = ("pi",)
    name = "stiff_pi"
    GAINS = ("kp_nm_s_rad", "ki_nm_rad", "torque_min_nm", "torque_max_nm")

    def __init__(self, h_s: float, impedance_nm_s_rad: float, top_drive_inertia_kg_m2: float, *,
                 kp_nm_s_rad: float | None = None, ki_nm_rad: float | None = None,
                 torque_min_nm: float = -DEFAULT_TORQUE_LIMIT_NM,
                 torque_max_nm: float = DEFAULT_TORQUE_LIMIT_NM) -> None:
        super().__init__(h_s, impedance_nm_s_rad, top_drive_inertia_kg_m2)
        kp = 50.0 * self.impedance_nm_s_rad if kp_nm_s_rad is None else kp_nm_s_rad
        ki = 5.0 * self.top_drive_inertia_kg_m2 if ki_nm_rad is None else ki_nm_rad
        self.pi = PI(self.h_s, kp, ki, torque_min_nm, torque_max_nm)

    def reset(self, speed_set_rad_s: float) -> None:
        super().reset(speed_set_rad_s)
        self.pi.q_nm = 0.0

    def error(self, measurement: SurfaceMeasurement) -> float:
        """Speed error e [rad/s] the PI acts on."""
        return self.speed_set_rad_s - measurement.top_drive_speed_rad_s

    def step(self, measurement: SurfaceMeasurement) -> float:
        return self.pi.output(self.error(measurement))

    def bumpless_start(self, current_output: float, measurement: SurfaceMeasurement) -> float:
        self.pi.load(check_number("current_output", current_output, low=None),
                     self.error(measurement))
        return self.step(measurement)


class SoftSpeed(Law):
    """SoftSpeed (Kyllingstad & Nessjøen, SPE/IADC 119660, 2009): a PI that is a damper at f_t.

    T_m = K_p e + K_i ∫e + J_c dΩ_TD/dt with K_p = k_p Z, K_i = (2π f_t)² (J_TD - J_c); the
    derivative is filtered (first order, ``derivative_corner_hz``). Defaults k_p = 4,
    f_t = 0.2 Hz, J_c = 0; tune f_t to the string's first mode (``tuning`` module).
    """

    __slots__ = ("compensated_inertia_kg_m2", "derivative", "pi", "tuning_frequency_hz")
    name = "soft_speed"
    GAINS = ("kp_over_impedance", "tuning_frequency_hz", "compensated_inertia_kg_m2",
             "derivative_corner_hz", "torque_min_nm", "torque_max_nm")

    def __init__(self, h_s: float, impedance_nm_s_rad: float, top_drive_inertia_kg_m2: float, *,
                 kp_over_impedance: float = 4.0, tuning_frequency_hz: float = 0.2,
                 compensated_inertia_kg_m2: float = 0.0, derivative_corner_hz: float = 5.0,
                 torque_min_nm: float = -DEFAULT_TORQUE_LIMIT_NM,
                 torque_max_nm: float = DEFAULT_TORQUE_LIMIT_NM) -> None:
        super().__init__(h_s, impedance_nm_s_rad, top_drive_inertia_kg_m2)
        gains = tune_soft_speed(self.impedance_nm_s_rad, self.top_drive_inertia_kg_m2,
                                f_t_hz=tuning_frequency_hz, kp_over_impedance=kp_over_impedance,
                                compensated_inertia_kg_m2=compensated_inertia_kg_m2)
        if gains.tuning_frequency_hz >= 0.5 / self.h_s:
            raise ParameterError(f"tuning_frequency_hz = {gains.tuning_frequency_hz!r} is out of "
                                 f"range: expected < the Nyquist frequency {0.5 / self.h_s:g} Hz")
        self.tuning_frequency_hz = gains.tuning_frequency_hz
        self.compensated_inertia_kg_m2 = gains.compensated_inertia_kg_m2
        self.pi = PI(self.h_s, gains.kp_nm_s_rad, gains.ki_nm_rad, torque_min_nm, torque_max_nm)
        self.derivative = FilteredDerivative(derivative_corner_hz, self.h_s,
                                             name="derivative_corner_hz")

    def reset(self, speed_set_rad_s: float) -> None:
        super().reset(speed_set_rad_s)
        self.pi.q_nm = 0.0
        self.derivative.settle(0.0)

    def step(self, measurement: SurfaceMeasurement) -> float:
        speed = measurement.top_drive_speed_rad_s
        feedforward = self.compensated_inertia_kg_m2 * self.derivative.step(speed)
        return self.pi.output(self.speed_set_rad_s - speed, feedforward)

    def bumpless_start(self, current_output: float, measurement: SurfaceMeasurement) -> float:
        speed = measurement.top_drive_speed_rad_s
        self.derivative.settle(speed)           # derivative 0 on the first step
        self.pi.load(check_number("current_output", current_output, low=None),
                     self.speed_set_rad_s - speed)
        return self.step(measurement)

