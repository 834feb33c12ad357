"""Reference tunings for the distributed string that keep the top passive up to its fifth
torsional mode (msg_docs/control.md, "Passive up to the fifth mode").

A law at the top of the pipe makes the top an impedance Z_top(jω) (``impedance``: the drive's
inertia and the sampled law, linearised). Where Re Z_top < 0 the top feeds the pipe's waves at
that frequency: a mode there loses damping, and a lightly damped higher mode can lock onto the
bit's regenerative instability. The lumped tunings (``reference``) took nothing above the first
mode into account, and on the distributed string SoftSpeed's compensated inertia and Z-Torque's
2.5 Hz torque low-pass made Re Z_top < 0 from ≈ 1 Hz and ≈ 1.8 Hz on base. Here the filters
are chosen so that Re Z_top ≥ 0 from 0 up to the fifth torsional mode f₅ (the pipe's natural
frequency with the drive's inertia at the top), for the sample period the law runs at:

- Z-Torque: the lowest torque low-pass, from its 2.5 Hz default up in steps of 25 %, that
  keeps the top passive (the speed low-pass and the gains stay the lumped rule's).
- SoftSpeed: the derivative's corner at 8 f₅, and the largest compensated inertia (from 95 %
  of the drive's down in steps of 5 %) that keeps the top passive.

Where no value below the Nyquist frequency does (a long sample period on a short string), the
closest is taken and ``passivity_margin_nm_s_rad`` says by how much it misses.
"""

from __future__ import annotations

import math

import numpy as np

from . import default_gains, make_law
from .impedance import top_boundary
from .laws import Law

PASSIVE_MODES = 5                 # the top passive up to this torsional mode
LOWPASS_STEP = 1.25               # Z-Torque's torque low-pass ladder, from its default up
FRACTION_STEP = 0.05              # SoftSpeed's compensated inertia ladder, from 0.95 down
DERIVATIVE_CORNER_PER_TOP_MODE = 8.0   # SoftSpeed's derivative corner / f₅
NYQUIST_SHARE = 0.4               # filter corners stay below this share of 1/h
POINTS = 400                      # frequencies the real part is checked at, up to f₅


def passivity_margin_nm_s_rad(law: Law, up_to_hz: float, lag_s: float = 0.0) -> float:
    """min Re Z_top(j 2π f) over 0 < f ≤ ``up_to_hz`` [N·m·s/rad]: ≥ 0, the top takes energy
    from the pipe's waves at every such frequency (``lag_s``: the drive's torque lag)."""
    f = np.linspace(up_to_hz / POINTS, up_to_hz, POINTS)
    s = 2j * np.pi * f
    k, lag = top_boundary(law, lag_s)(s)
    return float(np.min((k / (lag * s)).real))


def passive_gains(law: str, h_s: float, impedance_nm_s_rad: float,
                  top_drive_inertia_kg_m2: float, gains: dict[str, float], top_mode_hz: float,
                  lag_s: float = 0.0) -> dict[str, float]:
    """``gains`` with the filters of ``law`` chosen to keep the top passive up to
    ``top_mode_hz`` (module docstring); other laws' gains unchanged."""
    cap = NYQUIST_SHARE / h_s
    j = top_drive_inertia_kg_m2
    if law == "z_torque" and "torque_lowpass_hz" not in gains:   # a noisy speed keeps its own
        corner, ladder = default_gains(law)["torque_lowpass_hz"], []
        while corner <= cap:
            ladder.append({**gains, "torque_lowpass_hz": corner})
            corner *= LOWPASS_STEP
    elif law == "soft_speed":
        corner = min(DERIVATIVE_CORNER_PER_TOP_MODE * top_mode_hz, cap)
        top = round(gains["compensated_inertia_kg_m2"] / j / FRACTION_STEP)  # the rule's 95 %
        ladder = [{**gains, "derivative_corner_hz": corner,
                   "compensated_inertia_kg_m2": k * FRACTION_STEP * j}
                  for k in range(top, -1, -1)]
    else:
        return dict(gains)
    best, best_margin = dict(gains), -math.inf
    for trial in ladder:                        # the first passive one, else the closest
        built = make_law(law, h_s, impedance_nm_s_rad, j, **trial)
        margin = passivity_margin_nm_s_rad(built, top_mode_hz, lag_s)
        if margin >= 0.0:
            return trial
        if margin > best_margin:
            best, best_margin = trial, margin
    return best
