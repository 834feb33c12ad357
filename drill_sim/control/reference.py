"""The reference tunings the evaluation scores each law with (``reference_gains``), derived from
the string, the drive and the signals the law reads.

The laws' own defaults (NORCE Simulator4nDOF) suit long strings (first mode ≈ 0.2 Hz) and a
10 ms loop; a short string's first mode f₁ is faster (base: 0.76 Hz), so these rules set the
gains from f₁, the first torsional mode with the top drive's inertia J_TD, of the string model
the law runs on (``first_mode_frequency_hz``: lumped or distributed):

- SoftSpeed: f_t = f₁, J_c = 0.95 J_TD, derivative corner 25 f₁, so that its inertia
  compensation passes the mode with little lag.
- Z-Torque: K_p = max(50 Z, 6 J_TD ω₁), so that the drive's speed loop is stiff at the mode,
  and α = 0.5. Its pipe-torque estimate is fed back with the gain α K_p/Z, so its two signals
  must arrive aligned: it is told the drive's signals (``sensor_profile``: update period, each
  signal's filter), and with a noisy speed signal its torque low-pass comes down to 2 f₁.
- On the distributed string, whose higher modes these filters made the top feed, the filters
  keep the top passive up to the fifth torsional mode at the law's sample period (``passive``).
  Z-Torque there takes α = 0.3 (the top absorbs by swinging the drive's inertia, and 0.5 asked
  the motor for more than it has), with the saturation regulator backing α off (down to 0.15,
  at 0.3/s) to keep the motor on its limits about 3 % of the time, and the passive torque
  low-pass of exact signals in place of the noise rule's; for a drive's sampled or noisy
  signals that corner ω_T is capped at (α K_p/Z) ω_T ≤ 1100 rad/s (a measured bound) and the
  preset's ``commissioning`` gains apply. The lumped string's tunings are the rules above.

Why each rule, and the runs that set it: msg_docs/control.md, "Tuning for the node's rates"
(and "Passive up to the fifth mode", "Commissioned on long").
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
