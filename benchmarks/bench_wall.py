"""What the wall's friction costs the distributed string (msg_docs/model.md, "A deviated well
with friction along the string"): steps per second and the real-time factor with the wall and
without it (the same well, friction 0), on base's pipe drilling in a build (mu 0.3 / 0.25, the
preset's damping, steady start perturbed: stick-slip) and on field_a off bottom at 60 rpm,
timed from the end of its 10 s ramp (its own friction, 0.885 / 0.425: it breaks loose at
about 11 s and then sticks and slips), each at the model's step.

Run: .venv/bin/python benchmarks/bench_wall.py [--seconds 30]
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace

from drill_sim.core import load_preset
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.distributed_simulator import StringSimulator
from drill_sim.core.parameters import RigParameters
from drill_sim.core.rig import Rig
from drill_sim.core.well import Well

# vertical to 300 m, built to 40 deg at 700 m, then straight (tests/core/test_well.py's)
BUILD = ((0.0, 0.0, 0.0), (300.0, 0.0, 0.0), (700.0, 40.0, 0.0), (1200.0, 40.0, 0.0))


def base_build(mu: tuple[float, float], seconds: float) -> tuple[float, float]:
    """Steps per second and real-time factor of base's pipe drilling in the build."""
    p = load_preset("base")
    g = replace(p.string, well=Well(BUILD, friction_static=mu[0], friction_dynamic=mu[1]))
    params = RigParameters(**{**p.rig.as_dict(), **g.lumped()})
    h = 5e-4
    sim = StringSimulator(params.groups, geometry_waves(params, g, h))
    sim.start_steady(9.6, 1.32, 1e-3)
    sim.advance(1000)                                  # compiled, past the start
    n = round(seconds / (h * params.scales.time_s))
    began = time.perf_counter()
    sim.advance(n)
    took = time.perf_counter() - began
    return n / took, seconds / took


def field_a(friction: bool, seconds: float) -> tuple[float, float]:
    """Steps per second and real-time factor of field_a at 60 rpm off bottom, timed from the
    end of the 10 s ramp from rest (break-off, then stick-slip with the wall)."""
    preset = load_preset("field_a")
    g = preset.string
    if not friction:
        g = replace(g, well=replace(g.well, friction_static=0.0, friction_dynamic=0.0))
    rig = Rig(preset.rig, None, top_drive=preset.top_drive, string_model="distributed",
              geometry=g)
    rig.start_at_rest(0.05)
    for k in range(100):
        rig.command(0.01 * (k + 1) * 60.0 * math.pi / 30.0, preset.rig.submerged_weight_n)
        rig.advance_to(0.1 * (k + 1))
    steps = rig.sim.steps
    began = time.perf_counter()
    rig.advance_to(10.0 + seconds)
    took = time.perf_counter() - began
    return (rig.sim.steps - steps) / took, seconds / took


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--seconds", type=float, default=30.0, help="simulated time [s]")
    args = parser.parse_args()
    if not 1.0 <= args.seconds <= 3600.0:
        parser.error(f"--seconds {args.seconds:g}: expected 1 to 3600 s")
    print("case | wall | million steps/s | real-time factor")
    for label, mu in (("with", (0.3, 0.25)), ("without", (0.0, 0.0))):
        rate, rtf = base_build(mu, args.seconds)
        print(f"base in a build, drilling | {label} | {rate / 1e6:.2f} | {rtf:.0f}")
    for label, on in (("with", True), ("without", False)):
        rate, rtf = field_a(on, args.seconds)
        print(f"field_a off bottom, 60 rpm | {label} | {rate / 1e6:.2f} | {rtf:.0f}")


if __name__ == "__main__":
    main()
