"""The bit's rightmost on-bottom roots with the top held and with a top that reflects nothing
(the top section's own impedance W(s) = z r q at the top: the BHA then sees the pipe below the
top as a pure, damped dashpot), at the control map's sticking points (msg_docs/control.md,
"The control map"). If they agree, no top-end law moves them: the instability lives in the
BHA and the bit.

Run: .venv/bin/python benchmarks/absorbing_top.py
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from drill_sim.cli.case import si_case
from drill_sim.core import load_preset
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.stability import steady_state
from drill_sim.core.stability_distributed import characteristic, find_roots

POINTS = [("long", 40, 120), ("long", 40, 160), ("long", 55, 160), ("long", 70, 160),
          ("long", 100, 160), ("field_a", 40, 160), ("field_a", 55, 160), ("field_a", 70, 160),
          ("field_a", 40, 250)]
BOX = (-0.5, 5.0, -20.0, 20.0)


def rightmost(preset_name: str, rpm: float, wob_kn: float, absorbing: bool) -> complex:
    preset = load_preset(preset_name)
    case = si_case(preset, rpm, wob_kn)
    waves = geometry_waves(preset.rig, preset.string, 5e-4, continuous=True)
    t = waves.torsion
    z, eta, nu = float(t.z[0]), float(t.eta[0]), float(t.nu[0])

    def top(s):
        s = np.asarray(s, dtype=complex)
        w = z * np.sqrt(s * (s + nu)) * np.sqrt(1.0 + eta * s)
        return np.where(w.real < 0.0, -w, w), np.ones_like(s)     # Re W > 0: absorbing
    st = steady_state(case.groups, case.w0, case.omega0)
    roots = find_roots(BOX, lambda s: characteristic(
        s, case.groups, st, waves, top if absorbing else None), 80)
    roots = roots[(np.abs(roots) > 1e-7) & (roots.imag > 0.0)]
    return complex(roots[np.argmax(roots.real)])


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()
    print("preset | rpm | WOB [kN] | top held: rightmost s [1/t*] (Hz) | non-reflecting top")
    for name, rpm, wob in POINTS:
        hz = 1.0 / (2.0 * math.pi * load_preset(name).rig.scales.time_s)
        held, free = (rightmost(name, rpm, wob, a) for a in (False, True))
        print(f"{name} | {rpm} | {wob} | {held.real:+.3f} {held.imag:+.2f}i "
              f"({held.imag * hz:.2f} Hz) | {free.real:+.3f} {free.imag:+.2f}i")


if __name__ == "__main__":
    main()
