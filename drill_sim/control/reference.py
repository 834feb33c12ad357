"""The reference tunings the evaluation scores each law with, derived from the string.

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

f₁ is the lumped first torsional mode with the top's inertia (``first_mode_frequency_hz``).
"""

from __future__ import annotations

import math

from ..core.presets import Preset
from .tuning import first_mode_frequency_hz, pipe_impedance

COMPENSATED_FRACTION = 0.95       # J_c / J_TD of the reference SoftSpeed
DERIVATIVE_CORNER_PER_MODE = 25.0  # SoftSpeed's derivative corner / f₁
Z_TORQUE_ALPHA = 0.5               # the reference Z-Torque's α
STIFFNESS_AT_MODE = 6.0           # Z-Torque: K_p / (J_TD ω₁), at least


def reference_gains(law: str, preset: Preset, top_drive_inertia_kg_m2: float) -> dict[str, float]:
    """Gains of ``law`` tuned for this string and drive (empty: the law's defaults)."""
    f1 = first_mode_frequency_hz(preset, top_drive_inertia_kg_m2)
    z = pipe_impedance(preset)
    if law == "soft_speed":
        return {"tuning_frequency_hz": f1,
                "compensated_inertia_kg_m2": COMPENSATED_FRACTION * top_drive_inertia_kg_m2,
                "derivative_corner_hz": DERIVATIVE_CORNER_PER_MODE * f1}
    if law == "z_torque":
        stiff = STIFFNESS_AT_MODE * top_drive_inertia_kg_m2 * 2.0 * math.pi * f1
        return {"kp_nm_s_rad": max(50.0 * z, stiff), "alpha": Z_TORQUE_ALPHA}
    return {}
