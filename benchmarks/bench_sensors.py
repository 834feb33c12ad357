"""Cost of the rig's sensors per tick: ``SensorBank.measure`` on a real rig sample, for each
shipped profile (the node calls it once per tick, 1000 times a second at the default rate).

Prints µs per call, best of a few repeats, after JIT warm-up.

Run: .venv/bin/python benchmarks/bench_sensors.py
"""

from __future__ import annotations

import time

from drill_sim.core import Rig, load_preset
from drill_sim.core.sensor_profile import profile_names
from drill_sim.core.sensors import SensorBank


def per_call_us(profile: str, calls: int = 100_000, repeats: int = 3) -> float:
    preset = load_preset("base")
    rig = Rig(preset.rig)
    rig.start_steady(preset.top_drive_speed_rad_s, preset.hook_load_n, 1e-3)
    rig.advance(5.0)
    s = rig.sample()
    bank = SensorBank(profile, 1e-3, 1)
    t = 0.0
    for _ in range(1000):                       # warm-up
        t += 1e-3
        bank.measure(t, s)
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(calls):
            t += 1e-3
            bank.measure(t, s)
        best = min(best, (time.perf_counter() - start) / calls)
    return best * 1e6


def main() -> None:
    for name in profile_names():
        print(f"SensorBank.measure, profile {name:<12} {per_call_us(name):6.2f} µs per call")


if __name__ == "__main__":
    main()
