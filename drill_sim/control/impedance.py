"""A law at the top of the string, linearised: the top's dynamic stiffness it makes, for the
closed-loop roots of the distributed string (``drill_sim stability --string-model distributed
--law LAW``; msg_docs/control.md, "Closed-loop roots").

Small motions about a steady turn, SI, s in 1/s. The top drive's inertia J under the motor
torque T_m and the string's torque T_s at its top: J s Ω = T_m − T_s. A law answers the top's
speed Ω with T_m = −Y(s) Ω, so the top is the impedance Z_top = J s + Y(s), a dynamic
stiffness K(s) = s Z_top on the top's angle, returned as a pair (K, L) with K/L the stiffness
(L clears the law's own feedback loop, so neither has a pole in the upper half plane).

The law is the sampled one: each of its filters, its PI (rectangle rule), its windows and
lags by its own difference equation, evaluated at z = e^{sh}; its command held over the sample
(the hold's (1 − e^{−sh})/(sh)) and through the drive's lag 1/(1 + lag s). The motor torque a
law reads at a sample is the command of the sample before (z⁻¹). What this leaves out is
aliasing (the sampled response's images above the Nyquist frequency), small below it. Each law
answers the speed and the motor torque it reads, T_cmd = A Ω + B T_m (``law_responses``), with
C(z) its PI:

- stiff PI: A = −C, B = 0.
- SoftSpeed: A = −(C − J_c D(z)), D its filtered derivative; B = 0.
- Z-Torque: the pipe torque estimated from the motor torque's window mean M T_m and the
  speed's slope over the window S Ω, filtered by G (low-pass, high-pass, low-pass), fed back
  with a = α/Z into the set-point the PI follows through its speed filter L_Ω:
  A = −C (L_Ω − a G S), B = −C a G M.

With T_m = z⁻¹ T_cmd/(1 + lag s) and the top's torque the command held and lagged, H T_cmd:
Z_top = J s − H A/(1 − B z⁻¹/(1 + lag s)).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .filters import FirstOrderSection, HeldLag
from .laws import Kinematic, Law, Off, SoftSpeed, StiffPI
from .z_torque import ZTorque

Complex = complex | np.ndarray          # one s or an array of them
TopBoundary = Callable[[Complex], tuple[Complex, Complex]]


def section_response(section: FirstOrderSection, zi: Complex) -> Complex:
    """(b0 + b1 z⁻¹)/(1 + a1 z⁻¹) at z⁻¹ = ``zi``."""
    return (section.b0 + section.b1 * zi) / (1.0 + section.a1 * zi)


def lag_response(lag: HeldLag, zi: Complex) -> Complex:
    """y_k = x_{k-1} + (y_{k-1} − x_{k-1}) d: (1 − d) z⁻¹/(1 − d z⁻¹); τ = 0: 1."""
    if lag.tau_s == 0.0:
        return 1.0
    return (1.0 - lag.decay) * zi / (1.0 - lag.decay * zi)


def _check_modelled(law: Law) -> None:
    if not isinstance(law, (Off, StiffPI, SoftSpeed, ZTorque)):
        raise ValueError(f"law {law.name!r}: no linear model of its top boundary")


def law_responses(law: Law, zi: Complex) -> tuple[Complex, Complex]:
    """(A, B) at z⁻¹ = ``zi``: the sampled law's command per unit of the top speed it reads
    and per unit of the motor torque it reads, T_cmd = A Ω + B T_m (``off``: none)."""
    _check_modelled(law)
    if isinstance(law, Off):
        return 0.0, 0.0
    h, pi = law.h_s, law.pi                          # type: ignore[attr-defined]
    c = pi.kp_nm_s_rad + pi.ki_nm_rad * h / (1.0 - zi)
    if isinstance(law, StiffPI):
        return -c, 0.0
    if isinstance(law, SoftSpeed):
        d = law.derivative.corner_hz * 2.0 * np.pi * section_response(law.derivative.section, zi)
        return -(c - law.compensated_inertia_kg_m2 * d), 0.0
    a = law.alpha / law.impedance_nm_s_rad
    n = law.torque_window.n
    g = (section_response(law.lowpass_out, zi) * section_response(law.highpass, zi)
         * section_response(law.lowpass_torque, zi))
    mean = (1.0 - zi**n) / (n * (1.0 - zi))
    slope = law.top_drive_inertia_kg_m2 * (1.0 - zi**n) / (n * h) * lag_response(law.speed_lag,
                                                                              zi)
    speed = section_response(law.lowpass_speed, zi) - a * g * slope
    return -c * speed, -c * a * g * mean * lag_response(law.torque_lag, zi)


def top_boundary(law: Law, lag_s: float = 0.0) -> TopBoundary:
    """(K(s), L(s)) of ``law`` at the top of the string, SI [N·m/rad]: K/L is the dynamic
    stiffness T_top = −(K/L) φ_top the drive's inertia and the law present to the pipe. The
    motor torque the law reads is its command of the sample before, through the drive's lag;
    the top gets the command held and lagged: T_cmd (1 − B z⁻¹/(1 + lag s)) = A Ω."""
    if isinstance(law, Kinematic):
        raise ValueError("the kinematic pass-through holds the top's speed: its boundary is the "
                         "held top (no law)")
    _check_modelled(law)
    j, h = law.top_drive_inertia_kg_m2, law.h_s

    def boundary(s: Complex) -> tuple[Complex, Complex]:
        zi = np.exp(-h * s)
        lag = 1.0 + lag_s * s
        hold = (1.0 - zi) / (s * h) / lag
        a, b = law_responses(law, zi)
        loop = 1.0 - b * zi / lag
        return s * (j * s * loop - hold * a), loop
    return boundary
