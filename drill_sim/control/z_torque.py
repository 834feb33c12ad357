"""Z-Torque (Dwars, SPE/IADC 173037, 2015): torque feedback that matches the top to the pipe.

A top drive whose speed answers the pipe torque as Ω_TD = Ω_set - T_p/Z looks, to a wave coming
up the string, like more pipe: the wave is absorbed instead of reflected. Z-Torque obtains that
with a stiff speed PI whose error carries a torque term (as in the NORCE Simulator4nDOF):

    ω̂  = LPF_ω(Ω_TD)
    T̂_p = LPF_T(T_m - J_TD · dΩ_TD/dt)             estimated torque in the pipe at the top
    T̃  = LPF_T(HPF(T̂_p))                           its dynamic part
    e   = Ω_set - ω̂ - α T̃ / Z,   T_m = PI(e)

α (default 0.25) scales the match: the top then looks like Z/α to the pipe at the stick-slip
frequency, reflecting (α-1)/(α+1) of a speed wave (-0.6) where the stiff drive reflects -0.96.

The estimate is a difference of two large signals (T_m and J_TD dΩ/dt nearly cancel), fed back
with the gain α K_p / Z (≈ 140 when the drive is stiff at the base string's mode), so the two
must reach it aligned in time, or what is left of T_m closes a loop of its own. Aligned means:

- the speed's change over one sample against the torque applied over that sample (a backward
  difference, (Ω_k - Ω_k-1)/h, not a bilinear derivative, which is half a sample off: with
  100 Hz signals that alone drove the motor torque from limit to limit at 2 Hz);
- signals that update every ``measurement_period_s`` (a drive's 100 Hz signals read at 1 kHz)
  taken as the staircases they are: the torque's mean and the speed's change over that period
  (``filters.SampleWindow``);
- each signal through the other's filter too (``torque_signal_tau_s``, ``speed_signal_tau_s``:
  the first-order lag the drive puts on each), so both have passed the same chain.

A saturation regulator (off unless ``backoff_per_s`` > 0) keeps α within what the motor can
pay: the match makes the motor swing the drive's inertia, T_m ≈ (α K_p/Z) T_p at the higher
modes, and a motor on its limit matches nothing. While the PI's output is on a limit the α in
use falls at ``backoff_per_s`` (1 − s) [of the α set, per second], otherwise it climbs back at
``backoff_per_s`` s, s = ``saturation_target``, between ``alpha_min`` and α (a floor at or
above α: it never backs off): where α makes the motor saturate more than s of the time it
settles where it saturates s of the time, elsewhere α stays. It acts only on the limits, so
the linearised law (``impedance``) is unchanged.

Filters (``filters`` module: prewarped Tustin sections, corners exact at any sample rate):
LPF_ω 10 Hz, LPF_T 2.5 Hz, HPF 0.05 Hz. The HPF removes the mean drilling torque (which the PI's
integral carries) so that only oscillations are fed back; LPF_T bounds what the difference does
to speed noise: white noise σ sampled at f_s gives T̂_p a noise below J_TD ωc σ (ωc = 2π·2.5 Hz)
and T̃ about J_TD σ √(ωc³/(4 f_s)) -- 28 N·m for 0.01 rad/s at 1 kHz, against
J_TD √2 σ/h = 41 kN·m for the bare difference. The corners suit stick-slip at 0.1-0.76 Hz (the
T path's phase within 30° of zero); keep ``torque_lowpass_hz`` at least twice the stick-slip
frequency (three times with exact signals).
"""

from __future__ import annotations

from ..core.parameters import ParameterError, check_number
from .filters import FirstOrderSection, HeldLag, SampleWindow
from .laws import DEFAULT_TORQUE_LIMIT_NM, PI, Law, SurfaceMeasurement

MAX_MEASUREMENT_PERIOD_S = 1.0    # signals slower than this are no drive's speed and torque


class ZTorque(Law):
    """Z-Torque: a stiff speed PI on e = Ω_set - ω̂ - α T̃/Z (see the module docstring)."""

    __slots__ = ("alpha", "alpha_min", "alpha_scale", "backoff_per_s", "backoff_step",
                 "floor_scale", "highpass", "lowpass_out", "lowpass_speed", "lowpass_torque",
                 "measurement_period_s", "pi", "pipe_torque_estimate_nm", "saturation_target",
                 "speed_lag", "speed_window", "torque_feedback_nm", "torque_lag",
                 "torque_window")
    name = "z_torque"
    GAINS = ("alpha", "kp_nm_s_rad", "ki_nm_rad", "speed_lowpass_hz", "torque_lowpass_hz",
             "highpass_hz", "measurement_period_s", "torque_signal_tau_s",
             "speed_signal_tau_s", "torque_min_nm", "torque_max_nm", "alpha_min",
             "backoff_per_s", "saturation_target")

    def __init__(self, h_s: float, impedance_nm_s_rad: float, top_drive_inertia_kg_m2: float, *,
                 alpha: float = 0.25, kp_nm_s_rad: float | None = None,
                 ki_nm_rad: float | None = None, speed_lowpass_hz: float = 10.0,
                 torque_lowpass_hz: float = 2.5, highpass_hz: float = 0.05,
                 measurement_period_s: float = 0.0, torque_signal_tau_s: float = 0.0,
                 speed_signal_tau_s: float = 0.0,
                 torque_min_nm: float = -DEFAULT_TORQUE_LIMIT_NM,
                 torque_max_nm: float = DEFAULT_TORQUE_LIMIT_NM, alpha_min: float = 0.0,
                 backoff_per_s: float = 0.0, saturation_target: float = 0.03) -> None:
        super().__init__(h_s, impedance_nm_s_rad, top_drive_inertia_kg_m2)
        self.alpha = check_number("alpha", alpha, low_inclusive=True, high=10.0)
        # a floor at or above α: never backs off (α can be lowered without touching it)
        self.alpha_min = check_number("alpha_min", alpha_min, low_inclusive=True, high=10.0)
        self.backoff_per_s = check_number("backoff_per_s", backoff_per_s, low_inclusive=True,
                                          high=1.0 / h_s)
        self.saturation_target = check_number("saturation_target", saturation_target, high=0.5)
        self.backoff_step = self.backoff_per_s * h_s       # of the scale, per sample
        self.floor_scale = min(self.alpha_min / self.alpha, 1.0) if self.alpha > 0.0 else 1.0
        self.alpha_scale = 1.0       # α in use / α: below 1 only after the motor hit a limit
        kp = 50.0 * self.impedance_nm_s_rad if kp_nm_s_rad is None else kp_nm_s_rad
        ki = 5.0 * self.top_drive_inertia_kg_m2 if ki_nm_rad is None else ki_nm_rad
        self.pi = PI(self.h_s, kp, ki, torque_min_nm, torque_max_nm)
        h = self.h_s
        self.lowpass_speed = FirstOrderSection(speed_lowpass_hz, h, name="speed_lowpass_hz")
        self.lowpass_torque = FirstOrderSection(torque_lowpass_hz, h, name="torque_lowpass_hz")
        period = check_number("measurement_period_s", measurement_period_s,
                              low_inclusive=True, high=MAX_MEASUREMENT_PERIOD_S)
        n = max(1, round(period / h))
        self.measurement_period_s = n * h        # whole samples; 0 given: every sample
        self.torque_window = SampleWindow(n)
        self.speed_window = SampleWindow(n)
        # each signal through the other's filter: the speed through the torque signal's lag
        self.speed_lag = HeldLag(torque_signal_tau_s, h, name="torque_signal_tau_s")
        self.torque_lag = HeldLag(speed_signal_tau_s, h, name="speed_signal_tau_s")
        self.highpass = FirstOrderSection(highpass_hz, h, highpass=True, name="highpass_hz")
        self.lowpass_out = FirstOrderSection(self.lowpass_torque.corner_hz, h)
        if self.highpass.corner_hz >= self.lowpass_torque.corner_hz:
            raise ParameterError(f"highpass_hz = {self.highpass.corner_hz!r} is out of range: "
                                 f"expected < torque_lowpass_hz = "
                                 f"{self.lowpass_torque.corner_hz!r}")
        self.pipe_torque_estimate_nm = 0.0     # T̂_p of the last step [N·m]
        self.torque_feedback_nm = 0.0          # T̃ of the last step [N·m]

    @property
    def alpha_in_use(self) -> float:
        """The α the law feeds back with now: α, or less while the saturation regulator has
        backed it off."""
        return self.alpha * self.alpha_scale

    def _settle(self, speed_rad_s: float, motor_torque_nm: float) -> None:
        self.lowpass_speed.settle(speed_rad_s)
        self.lowpass_torque.settle(motor_torque_nm)
        self.speed_lag.settle(speed_rad_s)
        self.torque_lag.settle(motor_torque_nm)
        self.speed_window.settle(speed_rad_s)
        self.torque_window.settle(motor_torque_nm)
        self.highpass.settle(motor_torque_nm)
        self.lowpass_out.settle(0.0)
        self.alpha_scale = 1.0                 # taking over: the full match until a limit

    def reset(self, speed_set_rad_s: float) -> None:
        super().reset(speed_set_rad_s)
        self.pi.q_nm = 0.0
        self._settle(0.0, 0.0)
        self.pipe_torque_estimate_nm = 0.0
        self.torque_feedback_nm = 0.0

    def step(self, measurement: SurfaceMeasurement) -> float:
        speed = measurement.top_drive_speed_rad_s
        speed_hat = self.lowpass_speed.step(speed)
        aligned = self.speed_lag.step(speed)
        self.torque_window.push(self.torque_lag.step(measurement.motor_torque_nm))
        before = self.speed_window.push(aligned)
        slope = (aligned - before) / self.measurement_period_s     # dΩ/dt over the period
        t_p = self.lowpass_torque.step(self.torque_window.mean()
                                       - self.top_drive_inertia_kg_m2 * slope)
        t_tilde = self.lowpass_out.step(self.highpass.step(t_p))
        self.pipe_torque_estimate_nm = t_p
        self.torque_feedback_nm = t_tilde
        out = self.pi.output(self.speed_set_rad_s - speed_hat
                             - self.alpha_in_use * t_tilde / self.impedance_nm_s_rad)
        if self.backoff_per_s > 0.0:
            floor, step = self.floor_scale, self.backoff_step
            if out >= self.pi.torque_max_nm or out <= self.pi.torque_min_nm:
                scale = self.alpha_scale - step * (1.0 - self.saturation_target)
            else:
                scale = self.alpha_scale + step * self.saturation_target
            self.alpha_scale = min(max(scale, floor), 1.0)
        return out

    def bumpless_start(self, current_output: float, measurement: SurfaceMeasurement) -> float:
        """Filters settled on the measurement (no oscillation yet), integral loaded."""
        current = check_number("current_output", current_output, low=None)
        speed = check_number("top_drive_speed_rad_s", measurement.top_drive_speed_rad_s, low=None)
        self._settle(speed, check_number("motor_torque_nm", measurement.motor_torque_nm, low=None))
        self.pi.load(current, self.speed_set_rad_s - speed)
        return self.step(measurement)
