"""The pipe's damping, figure by figure: each shipped preset's damped modes off bottom (exact
pipe and the simulation's lines, top held), and on base at 60 rpm / 100 kN the surface
torque's line at the third torsional mode (3.27 Hz) and the stick-slip, lossless against the
preset's damped pipe (120 s after 60 s of drilling from a 1e-3 perturbation).

    python benchmarks/string_damping.py
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from drill_sim.core import DEFAULT_DT, load_preset
from drill_sim.core import kernel as kn
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.distributed_simulator import StringSimulator
from drill_sim.core.stability_distributed import string_modes
from drill_sim.core.top_drive import DriveGroups

LOSSLESS = {"torsional_damping_nm_s_per_rad_m": 0.0, "axial_damping_n_s_per_m2": 0.0,
            "torsional_retardation_time_s": 0.0, "axial_retardation_time_s": 0.0}


def modes_table() -> None:
    print("damped modes off bottom, top held: frequency Hz / damping ratio % "
          "(exact pipe | simulation's lines)")
    for name in ("base", "deep", "shallow"):
        p = load_preset(name)
        hz = 1.0 / (2.0 * math.pi * p.rig.scales.time_s)
        for continuous, label in ((True, "exact"), (False, "simulated")):
            res = string_modes(geometry_waves(p.rig, p.string, DEFAULT_DT, continuous=continuous),
                               p.rig.groups.psi, DriveGroups())
            for kind, modes in (("torsional", res.torsional), ("axial", res.axial)):
                row = ", ".join(f"{m.frequency * hz:.3f} / {100 * m.damping_ratio:.2f}"
                                for m in modes)
                print(f"  {name:8} {label:9} {kind:9} {row}")


def line_at(x: np.ndarray, dt_s: float, f_hz: float, width_hz: float = 0.15) -> float:
    """Amplitude of x's strongest line within width of f [same unit as x]."""
    x = (x - x.mean()) * np.hanning(x.size)
    spec = 2.0 * np.abs(np.fft.rfft(x)) / np.sum(np.hanning(x.size))
    f = np.fft.rfftfreq(x.size, dt_s)
    band = np.abs(f - f_hz) < width_hz
    return float(spec[band].max())


def on_bottom() -> None:
    p = load_preset("base")
    sc = p.rig.scales
    t_star = sc.time_s
    w0 = 1e3 * p.weight_on_bit_kn / sc.force_n
    print("base, 60 rpm, 100 kN, distributed string: 120 s after 60 s")
    for label, geometry in (("lossless", replace(p.string, **LOSSLESS)), ("damped", p.string)):
        sim = StringSimulator(p.rig.groups, geometry_waves(p.rig, geometry, DEFAULT_DT))
        sim.start_steady(w0, p.top_drive_speed_rad_s * t_star, 1e-3)
        sim.run(60.0 / t_star)
        interval = 0.002 / t_star
        rows = sim.record(120.0 / t_star, interval)
        ts_knm = rows[:, kn.O_TS] * sc.stiffness_nm_per_rad / 1e3
        bit_rpm = rows[:, kn.O_OMEGA] / t_star * 60.0 / (2.0 * math.pi)
        stuck = float(np.mean(rows[:, kn.O_REGIME] == kn.REGIME_STUCK))
        print(f"  {label:8} surface torque at 3.27 Hz {line_at(ts_knm, 0.002, 3.27):.2f} kN m "
              f"(at the first mode, 0.56 Hz: {line_at(ts_knm, 0.002, 0.56, 0.1):.2f}), "
              f"bit speed at 3.27 Hz {line_at(bit_rpm, 0.002, 3.27):.1f} rpm, "
              f"stuck {stuck:.3f} of the samples")


if __name__ == "__main__":
    modes_table()
    on_bottom()
