"""Runs of the kinematic top drive whose outputs ``data/kinematic_seed.npz`` holds as the seed's
stepper gave them (commit 16edf7b, before the top drive entered the stepper): the default mode
must still reproduce them bit for bit. Only the seed's API is used here, so the file can be
remade at that commit: ``python tests/core/seed_runs.py OUT.npz``."""

from __future__ import annotations

import dataclasses
import sys

import numpy as np

from drill_sim.core import Groups, Rig, Simulator, load_preset

ROW_FIELDS = ("tau", "u", "v", "phi", "omega", "w", "t", "ts", "delta_n", "stuck", "off_bottom",
              "omega0")


def _rows(name: str, tr, out: dict) -> None:
    out[f"{name}.rows"] = np.column_stack([getattr(tr, f).astype(float) for f in ROW_FIELDS])
    out[f"{name}.metrics"] = np.array(dataclasses.astuple(tr.metrics)[:18], dtype=float)


def seed_runs(**rig_options) -> dict[str, np.ndarray]:
    """Stick-slip on base, bouncing, a tag-bottom schedule from rest, and a Rig sampled in SI
    (``rig_options`` go to that Rig)."""
    out: dict[str, np.ndarray] = {}
    base = Groups(4, 13.73, 6.84, 0.36)
    sim = Simulator(base)
    sim.start_steady(9.6, 1.32, 1e-3)
    _rows("stick_slip", sim.run(120.0, output_interval=0.25), out)
    sim = Simulator(Groups(4, 50.0, 2.0, 0.36))
    sim.start_steady(6.0, 3.0, 1e-3)
    _rows("bouncing", sim.run(30.0, output_interval=0.25), out)
    sim = Simulator(base)
    sim.start_at_rest(gap=3.0)

    def schedule(tau: float) -> tuple[float, float]:
        return (0.0 if tau < 15 else min(9.6, 9.6 * (tau - 15) / 30.0),
                min(1.32, 1.32 * tau / 10.0))

    _rows("tag_bottom", sim.run(90.0, output_interval=0.25, schedule=schedule,
                                schedule_interval=0.05), out)
    preset = load_preset("base")
    rig = Rig(preset.rig, **rig_options)
    rig.start_steady(preset.top_drive_speed_rad_s, preset.hook_load_n, 1e-3)
    samples = []
    for k in range(100):
        rig.advance_to(0.2 * (k + 1))
        samples.append(tuple(float(v) for v in rig.sample()[:17]))
    out["rig.samples"] = np.array(samples)
    return out


if __name__ == "__main__":
    np.savez_compressed(sys.argv[1], **seed_runs())
