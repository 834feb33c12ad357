"""Real-time factor of the distributed string at the default step, on base and on a 4000 m
string, one core; prints the load average (other work on the machine slows it)."""

from __future__ import annotations

import os
import time
from dataclasses import replace

from drill_sim.core import DEFAULT_DT, load_preset
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.distributed_simulator import StringSimulator
from drill_sim.core.parameters import RigParameters


def real_time_factor(name: str, pipe_length_m: float | None = None, seconds: float = 600.0):
    p = load_preset(name)
    geometry = p.string if pipe_length_m is None else replace(p.string,
                                                              pipe_length_m=pipe_length_m)
    params = RigParameters(**{**p.rig.as_dict(), **geometry.lumped()})
    sc, groups = params.scales, params.groups
    waves = geometry_waves(params, geometry, DEFAULT_DT)
    sim = StringSimulator(groups, waves)
    w0 = 1e3 * p.weight_on_bit_kn / sc.force_n
    sim.start_steady(w0, p.top_drive_speed_rad_s * sc.time_s, 1e-3)
    sim.advance(10)                                   # compile / load the cache
    start = time.perf_counter()
    sim.run(seconds / sc.time_s)
    wall = time.perf_counter() - start
    m = sim.window_metrics()
    return seconds / wall, geometry.pipe_length_m, int(waves.torsion.steps.sum()), m.stick_fraction


if __name__ == "__main__":
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f}")
    for name, length in (("base", None), ("deep", 4000.0)):
        rtf, pipe, cells, stick = real_time_factor(name, length)
        print(f"{name}: {pipe:.0f} m of pipe, {cells} torsional cells, stick fraction "
              f"{stick:.3f}, real-time factor {rtf:.0f}")
    print(f"step {DEFAULT_DT} t*; targets: >= 200 on base, >= 50 on 4000 m")
