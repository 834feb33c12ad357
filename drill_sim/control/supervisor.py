"""A law in service: chosen and re-tuned at run time, enabled and disabled without a bump, with
the figures a status report needs (saturation, wind-up). No ROS: the controller node is a thin
adapter around it, and the offline loop and tests use it directly.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping

from ..core.parameters import ParameterError, check_number
from ..core.top_drive import DEFAULT_TORQUE_LIMIT_NM
from . import LAWS, make_law
from .laws import Law, SurfaceMeasurement
from .policy import POLICY_LAW, Policy, PolicyLaw


class Supervisor:
    """One law at sample period ``h_s`` [s], pipe impedance Z [N·m·s/rad] and J_TD [kg·m²].

    ``step(m)`` returns the command for this sample, or None while disabled (the drive keeps
    what it had). Enabling takes over from the motor torque the drive applies now (the
    measurement's ``motor_torque_nm``); a new law or new gains take over from the last output.
    """

    def __init__(self, h_s: float, impedance_nm_s_rad: float, top_drive_inertia_kg_m2: float,
                 law: str = "z_torque", gains: Mapping[str, float] | None = None, *,
                 enabled: bool = True, speed_set_rad_s: float = 0.0,
                 policy: Policy | None = None) -> None:
        self.h_s, self.z, self.j = h_s, impedance_nm_s_rad, top_drive_inertia_kg_m2
        self.policy = policy              # what law "policy" runs (``control.policy``)
        self.law = self.build(law, gains or {})
        self.speed_set_rad_s = check_number("speed_set_rad_s", speed_set_rad_s, low=None)
        self.law.reset(self.speed_set_rad_s)
        self.enabled = bool(enabled)
        self._started = False             # the law has taken over since the last enable
        self.last_output: float | None = None
        self.samples = self.saturated = self.wound_up = 0

    def build(self, law: str, gains: Mapping[str, float]) -> Law:
        """A law of these gains (ParameterError naming a bad one); nothing changes here."""
        if law == POLICY_LAW:
            if self.policy is None:
                raise ParameterError("law = 'policy' needs a policy: expected policy = "
                                     "package.module:callable")
            if gains:
                raise ParameterError(f"law 'policy' has no gains; got {sorted(gains)}")
            return PolicyLaw(self.h_s, self.z, self.j, self.policy)
        if law in LAWS and LAWS[law].output_kind != "torque":
            torque_laws = ", ".join(n for n, c in LAWS.items() if c.output_kind == "torque")
            raise ParameterError(f"law = {law!r} is a speed pass-through, not a controller "
                                 f"of the motor torque: expected one of {torque_laws}")
        return make_law(law, self.h_s, self.z, self.j, **dict(gains))

    def replace_law(self, law: str, gains: Mapping[str, float]) -> None:
        """Switch to ``law`` with ``gains``; bumpless: it takes over from the last output."""
        new = self.build(law, gains)
        new.reset(self.speed_set_rad_s)
        self.law = new
        self._started = False

    def set_speed(self, speed_set_rad_s: float) -> None:
        self.speed_set_rad_s = check_number("speed_set_rad_s", speed_set_rad_s, low=None)
        self.law.set_speed(self.speed_set_rad_s)

    def set_enabled(self, enabled: bool) -> None:
        if enabled and not self.enabled:
            self._started = False
            self.last_output = None           # take over from what the drive applies
        self.enabled = bool(enabled)

    def step(self, m: SurfaceMeasurement) -> float | None:
        if not self.enabled:
            return None
        if not self._started:
            current = m.motor_torque_nm if self.last_output is None else self.last_output
            out = self.law.bumpless_start(current, m)
            self._started = True
        else:
            out = self.law.step(m)
        self.last_output = out
        self.samples += 1
        limits = self.limits()
        if limits is not None:                     # the law's PI and its limits
            low, high = limits
            pi = self.law.pi                       # type: ignore[attr-defined]
            tol = 1e-9 * (high - low)
            if out >= high - tol or out <= low + tol:
                self.saturated += 1
            if pi.q_nm >= high - tol or pi.q_nm <= low + tol:
                self.wound_up += 1
        return out

    def limits(self) -> tuple[float, float] | None:
        """The law's output limits [N·m] (None: a law without them)."""
        pi = getattr(self.law, "pi", None)
        return None if pi is None else (pi.torque_min_nm, pi.torque_max_nm)

    def take_window(self) -> dict[str, float]:
        """Figures since the previous call: samples, saturation and wind-up fractions."""
        n = self.samples
        out = {"samples": n, "saturation_fraction": self.saturated / n if n else 0.0,
               "windup_fraction": self.wound_up / n if n else 0.0}
        self.samples = self.saturated = self.wound_up = 0
        return out


def law_gain_defaults(law: str, impedance_nm_s_rad: float, top_drive_inertia_kg_m2: float
                      ) -> dict[str, float]:
    """Every gain of ``law`` with its default as a number, as a controller offers them before
    it is tuned: K_p 50 Z, K_i 5 J_TD where the law leaves them to Z and J_TD, and the base
    drive's torque rating (±60 kN·m) as limits."""
    sig = inspect.signature(LAWS[law].__init__)
    out = {}
    for name in LAWS[law].GAINS:
        value = sig.parameters[name].default
        if value is None:                          # K_p and K_i: left to Z and J_TD
            value = {"kp_nm_s_rad": 50.0 * impedance_nm_s_rad,
                     "ki_nm_rad": 5.0 * top_drive_inertia_kg_m2}[name]
        elif name == "torque_min_nm":
            value = -DEFAULT_TORQUE_LIMIT_NM
        elif name == "torque_max_nm":
            value = DEFAULT_TORQUE_LIMIT_NM
        out[name] = float(value)
    return out
