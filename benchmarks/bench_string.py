"""Real-time factor of the distributed string at the default step, on base and on a 4000 m
string, one core; and what one 1 ms node tick costs the model (Rig.advance_to + Rig.sample,
as the node calls them) on both string models, kinematic and torque-mode drive. Prints the
load average (other work on the machine slows it)."""

from __future__ import annotations

import os
import time
from dataclasses import replace

import numpy as np

from drill_sim.core import DEFAULT_DT, Rig, load_preset
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.distributed_simulator import StringSimulator
from drill_sim.core.parameters import RigParameters
from drill_sim.core.top_drive import TopDriveParameters


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


def tick_cost_us(model: str, mode: str, ticks: int = 20000) -> tuple[float, float]:
    """(median, p99) [us] of one 1 ms tick of the model on base in stick-slip."""
    p = load_preset("base")
    rig = Rig(p.rig, string_model=model, geometry=p.string,
              top_drive=TopDriveParameters(top_drive_mode=mode))
    rig.start_steady(p.top_drive_speed_rad_s, p.hook_load_n, perturbation=1e-3)
    rig.advance(30.0)
    cost = np.empty(ticks)
    t = rig.time_s
    for i in range(ticks):
        t += 1e-3
        start = time.perf_counter()
        rig.advance_to(t)
        rig.sample()
        cost[i] = time.perf_counter() - start
    return float(np.median(cost)) * 1e6, float(np.percentile(cost, 99)) * 1e6


if __name__ == "__main__":
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f}")
    for name, length in (("base", None), ("deep", 4000.0)):
        rtf, pipe, cells, stick = real_time_factor(name, length)
        print(f"{name}: {pipe:.0f} m of pipe, {cells} torsional cells, stick fraction "
              f"{stick:.3f}, real-time factor {rtf:.0f}")
    print(f"step {DEFAULT_DT} t*; targets: >= 200 on base (set for the lossless pipe), >= 50 "
          "on 4000 m")
    for model in ("lumped", "distributed"):
        for mode in ("kinematic", "torque"):
            med, p99 = tick_cost_us(model, mode)
            print(f"1 ms node tick, model only (advance_to + sample), base, {model} string, "
                  f"{mode} drive: median {med:.1f} us, p99 {p99:.1f} us")
