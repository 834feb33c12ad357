"""Speed of the physics core: steps per second, real-time factor, and start-up time.

Prints (issue targets in brackets):
  - steps per second of the stepper, base preset in stick-slip at the default dt, one core,
    after JIT warm-up [>= 20 million]: the seed's kinematic top drive, then the top drive in the
    loop under its speed PI (``speed`` mode, the preset's drive);
  - real-time factor, simulated seconds per wall second [>= 1000];
  - time from a fresh process start to the first completed step, numba cache warm [< 1 s]
    and cold (an empty cache directory).

Run: .venv/bin/python benchmarks/bench_core.py
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import tempfile
import time

FIRST_STEP = (
    "from drill_sim.core import Rig, load_preset\n"
    "p = load_preset('base'); rig = Rig(p.rig)\n"
    "rig.start_steady(p.top_drive_speed_rad_s, p.hook_load_n)\n"
    "rig.advance_to(rig.dt_s)\n"
    "print('stepped', rig.steps)\n"
)


def steps_per_second(steps: int = 20_000_000, repeats: int = 5,
                     mode: str = "kinematic") -> tuple[float, float, float]:
    from drill_sim.core import Rig, load_preset
    preset = load_preset("base")
    rig = Rig(preset.rig, top_drive=dataclasses.replace(preset.top_drive, top_drive_mode=mode))
    rig.start_steady(preset.top_drive_speed_rad_s, preset.hook_load_n, 1e-3)
    rig.advance(30.0)                                  # warm-up and into stick-slip
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        rig.advance_steps(steps)
        best = min(best, time.perf_counter() - t0)
    stick = rig.metrics()["stick_fraction"]
    return steps / best, steps * rig.dt_s / best, stick


def first_step_seconds(cache_dir: str | None) -> float:
    env = dict(os.environ)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = cache_dir
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", FIRST_STEP], env=env, capture_output=True,
                         text=True, check=True).stdout
    elapsed = time.perf_counter() - t0
    assert "stepped 1" in out, out
    return elapsed


def main() -> None:
    for mode in ("kinematic", "speed"):
        rate, rtf, stick = steps_per_second(mode=mode)
        print(f"stepper, {mode} top drive: {rate / 1e6:.1f} million steps/s, real-time factor "
              f"{rtf:.0f} (base preset, default dt, stick fraction {stick:.2f})")
    with tempfile.TemporaryDirectory() as cold:
        cold_s = first_step_seconds(cold)
        first_step_seconds(None)                       # make sure the default cache is warm
        warm_s = min(first_step_seconds(None) for _ in range(3))
    print(f"fresh process to first completed step: {warm_s:.2f} s with the numba cache warm, "
          f"{cold_s:.2f} s cold")


if __name__ == "__main__":
    main()
