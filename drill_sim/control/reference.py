"""The reference tunings the evaluation scores each law with, derived from the string, the drive
and the signals the law reads.

The laws' own defaults are those of the NORCE Simulator4nDOF, chosen for long strings (first
mode ≈ 0.2 Hz) and a 10 ms loop. On a short string the first mode is faster (base: 0.76 Hz)
and two things the defaults take for granted stop holding (msg_docs/control.md, "Tuning for
the node's rates"):

- Z-Torque needs the drive's speed loop to be stiff *at the mode*, K_p ≫ J_TD ω₁, so that the
  top follows Ω_set − α T̃/Z; with K_p = 50 Z = 15.1 kN·m·s/rad and J_TD ω₁ = 13.9 kN·m·s/rad
  on base the top's admittance lags by ≈ 45° before any filter and the match is lost. Rule:
  K_p = max(50 Z, 6 J_TD ω₁). α = 0.5: with 0.25 Z-Torque keeps stick-slip from growing but,
  switched on in established stick-slip, clears it at only some switch instants (base, 60 rpm,
  100 kN: 2 of 4); with 0.5 at all of them.
- SoftSpeed's inertia compensation differentiates the speed; its filter must pass the mode
  with little lag: corner 25 f₁ (19 Hz on base, against 5 Hz by default). J_c = 0.95 J_TD,
  f_t = f₁.

Z-Torque's pipe-torque estimate T_m − J_TD dΩ/dt is fed back with a gain α K_p/Z ≈ 140, so its
two signals must reach it aligned (``z_torque``): with a sensor profile, the law is told what
the drive's signals are -- how often they update (the slower of the speed's and the motor
torque's rates) and each one's first-order filter -- as an engineer reads them off the drive's
data sheet. When the speed signal is noisy the torque low-pass comes down to 2 f₁ (1.5 Hz on
base: 2.4 times less motor-torque noise for 20° more lag at the mode).

f₁ is the first torsional mode with the top's inertia (``first_mode_frequency_hz``), of the
string model the law will run on: lumped √(C(1/I + 1/J_TD)), or the distributed pipe's own
frequency equation (base: 0.76 and 0.57 Hz).

On the distributed string the pipe's higher modes are there too, and these rules' filters made
the top feed them (Re Z_top < 0 from ~1 Hz for SoftSpeed, ~1.8 Hz for Z-Torque on base): there
the filters are then chosen for a top passive up to the fifth mode (``passive``), for the law's
sample period. For Z-Torque that filter is chosen on exact signals and then replaces the noise
rule's low one too: with a drive's 10 ms signals no low-pass keeps the linearised top passive
up to f₅ (on long Re Z_top < 0 from ≈ 1.1 Hz whatever the corner), the ladder's closest was a
339 Hz corner that ran the motor from limit to limit, and the noise rule's 0.47 Hz on long left
the law blind to the 1.2 Hz stick-slip of 100 rpm / 160 kN (stuck 0.24 with ``surface_rig``,
0.00 with the exact signals' 7.6 Hz). With such signals (or a noisy speed) what is left of T_m
in the pipe-torque estimate (their lags, their staircase, the noise) is fed back with the gain
α K_p/Z, a loop whose gain grows with the low-pass's corner ω_T; so ω_T is capped at (α K_p/Z)
ω_T = 1100 rad/s, a bound measured between two failures, not derived: on base (K_p 62
kN·m·s/rad) the exact signals' 29 Hz put the motor on a limit 61 % of the time and 3.2 Hz 12 %,
2.5 Hz 1 % (five starts); on long (26 kN·m·s/rad) 4.7 Hz left 100 rpm / 160 kN stuck 0.05. It
takes base to 2.9 Hz and long to 6.8 Hz, and leaves field_a's 9.5 Hz. And α comes down to 0.3:
on a long string the top absorbs by swinging the drive's inertia, and α 0.5 asked the motor for
more than its 60 kN·m 7-9 % of the time where 0.3 cures the same points at 0-2 %
(msg_docs/control.md, "The control map"). Where even that is more than the motor can pay
(field_a at 250 kN, whose wall takes 16 of the 60 kN·m: on its limit 6-21 % of the time at 0.3,
and 0.2 loses long's 100 rpm / 160 kN), α backs off to keep the motor on its limits about 3 % of
the time, down to 0.15 (``z_torque``'s saturation regulator, 0.3/s). The lumped string's
tunings are these rules, unchanged.

Where the rules fall short on one string, the preset says so: its ``commissioning`` section
sets Z-Torque's gains on that string for a drive's sampled or noisy signals (the distributed
string only), as a drive's controller is commissioned on its rig. long's: a 4.5 Hz speed
low-pass and a 0.08 Hz high-pass, which cure its 100 rpm / 160 kN through ``surface_rig``
(stuck 0.014 over 40 starts with the rule's 10 and 0.05 Hz) and would lose field_a's 55 rpm /
250 kN as a rule (msg_docs/control.md, "Commissioned on long").
"""

from __future__ import annotations

import math
from pathlib import Path

from ..core.parameters import ParameterError
from ..core.presets import Preset
from ..core.sensor_profile import SensorProfile, load_profile
from .tuning import first_mode_frequency_hz, pipe_impedance, torsional_modes_hz

COMPENSATED_FRACTION = 0.95       # J_c / J_TD of the reference SoftSpeed
DERIVATIVE_CORNER_PER_MODE = 25.0  # SoftSpeed's derivative corner / f₁
Z_TORQUE_ALPHA = 0.5               # the reference Z-Torque's α
DISTRIBUTED_Z_TORQUE_ALPHA = 0.3   # its α on the distributed string (see the docstring)
DISTRIBUTED_Z_TORQUE_BACKOFF = {"alpha_min": 0.15, "backoff_per_s": 0.3,
                                "saturation_target": 0.03}   # α within the motor's limits
STIFFNESS_AT_MODE = 6.0           # Z-Torque: K_p / (J_TD ω₁), at least
NOISY_TORQUE_LOWPASS_PER_MODE = 2.0   # Z-Torque's LPF_T / f₁ when the speed signal is noisy
SIGNAL_GAINS = ("measurement_period_s", "torque_signal_tau_s", "speed_signal_tau_s")
SIGNAL_LOOP_BANDWIDTH_RAD_S = 1100.0   # distributed, a drive's signals: (α K_p/Z) ω_T at most


def reference_gains(law: str, preset: Preset, top_drive_inertia_kg_m2: float, *,
                    string_model: str = "lumped",
                    sensor_profile: str | Path | SensorProfile | None = None,
                    sample_period_s: float = 1e-3) -> dict[str, float]:
    """Gains of ``law`` tuned for this string and drive, and (Z-Torque) for the signals of
    ``sensor_profile`` (None or ``ideal``: exact signals every sample); empty: the law's
    defaults. On the distributed string the filters are then chosen for a top passive up to
    the fifth torsional mode at the law's ``sample_period_s`` [s] (``passive``), and a drive's
    signals take the preset's commissioned Z-Torque gains (checked here whatever the string
    and signals: ``check_commissioning``)."""
    check_commissioning(preset, sample_period_s)
    gains = _lumped_rule(law, preset, top_drive_inertia_kg_m2, string_model, sensor_profile)
    if string_model != "distributed":
        return gains
    from .passive import PASSIVE_MODES, passive_gains
    signals: dict[str, float] = {}
    noisy = False
    if law == "z_torque":         # the filter passive on exact signals, and a gentler α
        noisy = "torque_lowpass_hz" in gains      # the noise rule fired: a noisy speed
        signals = {k: v for k, v in gains.items() if k in SIGNAL_GAINS}
        gains = {k: v for k, v in gains.items()
                 if k not in SIGNAL_GAINS and k != "torque_lowpass_hz"}
        gains["alpha"] = DISTRIBUTED_Z_TORQUE_ALPHA
        gains.update(DISTRIBUTED_Z_TORQUE_BACKOFF)
    top_mode = torsional_modes_hz(preset.rig, preset.string, float(top_drive_inertia_kg_m2))
    z = pipe_impedance(preset)
    tuned = passive_gains(law, sample_period_s, z, top_drive_inertia_kg_m2, gains,
                          top_mode[PASSIVE_MODES - 1], preset.top_drive.drive_lag_s)
    if signals or noisy:          # a drive's signals: the estimate's residual loop bounded
        cap_hz = SIGNAL_LOOP_BANDWIDTH_RAD_S * z / (tuned["alpha"] * tuned["kp_nm_s_rad"])
        tuned["torque_lowpass_hz"] = min(tuned["torque_lowpass_hz"], cap_hz / (2.0 * math.pi))
        tuned.update(preset.commissioned(law))
    return {**tuned, **signals}


def check_commissioning(preset: Preset, sample_period_s: float = 1e-3) -> None:
    """Refuse a ``commissioning`` section that names a law other than Z-Torque (the law that
    reads a drive's signals, so the only one it applies to), an unknown gain, or a value out
    of the gain's range (each over the law's defaults at ``sample_period_s`` [s]), naming the
    preset and the entry; whether or not this run's string and signals would use it."""
    from .z_torque import ZTorque
    for name, pairs in preset.commissioning:
        where = f"preset {preset.name!r}: commissioning.{name}"
        if name != ZTorque.name:
            raise ParameterError(f"{where}: only {ZTorque.name}'s gains are commissioned (the "
                                 f"law that reads a drive's signals): expected {ZTorque.name}, "
                                 f"got {name!r}")
        gains = dict(pairs)
        unknown = sorted(set(gains) - set(ZTorque.GAINS))
        if unknown:
            raise ParameterError(f"{where}: unknown gain(s) {unknown}; expected "
                                 f"{', '.join(ZTorque.GAINS)}")
        try:        # a high-pass is checked against the rule's torque low-pass where built
            ZTorque(sample_period_s, 1.0, 1.0, **{"torque_lowpass_hz": 0.25 / sample_period_s,
                                                  **gains})
        except ParameterError as exc:
            raise ParameterError(f"{where}: {exc}") from None


def _lumped_rule(law: str, preset: Preset, top_drive_inertia_kg_m2: float, string_model: str,
                 sensor_profile: str | Path | SensorProfile | None) -> dict[str, float]:
    """The rules above, from f₁ of ``string_model``."""
    f1 = first_mode_frequency_hz(preset, top_drive_inertia_kg_m2, string_model=string_model)
    z = pipe_impedance(preset)
    if law == "soft_speed":
        return {"tuning_frequency_hz": f1,
                "compensated_inertia_kg_m2": COMPENSATED_FRACTION * top_drive_inertia_kg_m2,
                "derivative_corner_hz": DERIVATIVE_CORNER_PER_MODE * f1}
    if law == "z_torque":
        stiff = STIFFNESS_AT_MODE * top_drive_inertia_kg_m2 * 2.0 * math.pi * f1
        return {"kp_nm_s_rad": max(50.0 * z, stiff), "alpha": Z_TORQUE_ALPHA,
                **signal_alignment(sensor_profile, f1)}
    return {}


def signal_alignment(sensor_profile: str | Path | SensorProfile | None,
                     first_mode_hz: float) -> dict[str, float]:
    """Z-Torque's gains that say what its speed and motor-torque signals are: their update
    period and each one's filter; and a lower torque low-pass if the speed is noisy."""
    if sensor_profile is None:
        return {}
    profile = (sensor_profile if isinstance(sensor_profile, SensorProfile)
               else load_profile(sensor_profile))
    speed = profile.channels["top_drive_speed_rad_s"]
    torque = profile.channels["motor_torque_nm"]
    out = {}
    period = max(speed.period_s, torque.period_s)
    if period > 0.0:
        out["measurement_period_s"] = period
    if torque.filter_tau_s > 0.0:
        out["torque_signal_tau_s"] = torque.filter_tau_s
    if speed.filter_tau_s > 0.0:
        out["speed_signal_tau_s"] = speed.filter_tau_s
    if speed.noise_std > 0.0:
        out["torque_lowpass_hz"] = NOISY_TORQUE_LOWPASS_PER_MODE * first_mode_hz
    return out
