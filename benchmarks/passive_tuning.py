"""The reference tunings on the distributed string, mode by mode: the top's real part Re Z_top
at each of the first five torsional modes (>= 0: passive there) and the closed loop's damping
ratios, against the drive with its motor torque held (msg_docs/control.md, "Passive up to the
fifth mode").

    python benchmarks/passive_tuning.py [--presets base,long,field_a] [--sample-period 0.001]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace

import numpy as np

from drill_sim.control import default_gains, make_law
from drill_sim.control.impedance import top_boundary
from drill_sim.control.reference import (
    COMPENSATED_FRACTION,
    DERIVATIVE_CORNER_PER_MODE,
    reference_gains,
)
from drill_sim.control.tuning import pipe_impedance, torsional_modes_hz
from drill_sim.core import DEFAULT_DT, load_preset
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.stability_distributed import string_modes


def lumped_rule(law: str, j: float, f1: float) -> dict[str, float] | None:
    """The lumped rule's filters (``control.reference``), where they differ."""
    return {"soft_speed": {"compensated_inertia_kg_m2": COMPENSATED_FRACTION * j,
                           "derivative_corner_hz": DERIVATIVE_CORNER_PER_MODE * f1},
            "z_torque": {"torque_lowpass_hz": default_gains("z_torque")["torque_lowpass_hz"]},
            }.get(law)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--presets", default="base,long,field_a")
    ap.add_argument("--sample-period", type=float, default=1e-3)
    a = ap.parse_args()
    h = a.sample_period
    for name in a.presets.split(","):
        preset = load_preset(name)
        rig, j = preset.rig, preset.top_drive.top_drive_inertia_kg_m2
        ts, c = rig.scales.time_s, rig.scales.stiffness_nm_per_rad
        waves = geometry_waves(rig, preset.string, DEFAULT_DT)
        f = np.array(torsional_modes_hz(rig, preset.string, j))
        print(f"\n{name}: torsional modes {', '.join(f'{x:.3f}' for x in f)} Hz, h = {h:g} s, "
              f"Z = {pipe_impedance(preset):.0f} N m s/rad")
        print("| top | gains | Re Z_top at modes 1-5 [N·m·s/rad] | closed-loop modes, Hz / "
              "damping % |")
        print("| --- | --- | --- | --- |")
        held = replace(preset.top_drive, top_drive_mode="torque")
        modes = string_modes(waves, rig.groups.psi, held.groups(rig.scales,
                                                                 rig.bha_inertia_kg_m2), 5)
        print(f"| motor torque held | | 0 | {_modes(modes, ts)} |")
        for law_name in ("stiff_pi", "soft_speed", "z_torque"):
            rows = [("reference", reference_gains(law_name, preset, j, string_model="distributed",
                                                  sample_period_s=h))]
            if (rule := lumped_rule(law_name, j, f[0])) is not None:
                rows.append(("lumped rule", {**rows[0][1], **rule}))
            for label, gains in rows:
                law = make_law(law_name, h, pipe_impedance(preset), j, **gains)
                boundary = top_boundary(law, preset.top_drive.drive_lag_s)
                s = 2j * np.pi * f
                k, lag = boundary(s)
                real = (k / (lag * s)).real

                def top(x, boundary=boundary, ts=ts, c=c):
                    kk, ll = boundary(x / ts)
                    return kk / c, ll
                closed = string_modes(waves, rig.groups.psi, held.groups(
                    rig.scales, rig.bha_inertia_kg_m2), 5, top=top)
                shown = ", ".join(f"{k_}={v:.4g}" for k_, v in gains.items())
                print(f"| {law_name} ({label}) | {shown} | "
                      f"{', '.join(f'{x:.0f}' for x in real)} | {_modes(closed, ts)} |")
    return 0


def _modes(modes, ts: float) -> str:
    return ", ".join(f"{m.root.imag / ts / (2 * np.pi):.3f} / {100 * m.damping_ratio:.1f}"
                     for m in modes.torsional)


if __name__ == "__main__":
    sys.exit(main())
