"""Throughput of the vector environment (``gymnasium.make_vec("drill_sim/Rig-v0", num_envs=N)``)
against the compiled single-rig stepper and a single environment stepped from Python.

A rig-tick is one control period (``--period``, default 10 ms) of one rig. Prints rig-ticks
per second:
  - the compiled stepper of ``drill_sim simulate`` (one ``Rig`` advanced over a long run, no
    Python between ticks): the ceiling per core;
  - one ``RigEnv`` stepped from Python;
  - the vector environment with N = 1, 16, 64, 256 rigs on one core, and on every core (one
    process per core, each with N / cores rigs), with the share of the stepper's figure per
    core and the gain over the single environment.
The policy holds each drive's torque (the observation's motor torque): its cost is nil. The
rigs draw the grid scenarios (stick-slip at some points), ideal sensors unless told.

Run: .venv/bin/python benchmarks/bench_vector.py [--seconds 3] [--period 0.01] [--mode torque]
     [--string-model lumped|distributed] [--sensor-profile ideal] [--sizes 1 16 64 256]
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import time

import numpy as np


def stepper_ticks_per_s(period_s: float, seconds: float, string_model: str) -> float:
    """The compiled stepper's rig-ticks per wall second: one rig, long advances."""
    from drill_sim.core import Rig, load_preset
    from drill_sim.gym import RigEnv
    preset = load_preset("base")
    env = RigEnv("base", control_period_s=period_s, string_model=string_model)
    env.reset(seed=0)
    rig = Rig(preset.rig, env.loop.rig.dt_s, top_drive=env.loop.rig.top_drive,
              string_model=string_model, geometry=preset.string)
    rig.start_steady(preset.top_drive_speed_rad_s, preset.hook_load_n, 1e-3)
    rig.advance(1.0)                                   # compiled, and into its motion
    steps = max(1, round(seconds / rig.dt_s))
    t0 = time.perf_counter()
    rig.advance_steps(steps)
    wall = time.perf_counter() - t0
    return steps * rig.dt_s / period_s / wall


def single_env_ticks_per_s(period_s: float, seconds: float, mode: str, **kwargs) -> float:
    from drill_sim.gym import RigEnv
    env = RigEnv("base", control_period_s=period_s, top_drive_mode=mode, **kwargs)
    obs, _ = env.reset(seed=0)
    column = 1 if mode == "torque" else 4
    for _ in range(5):
        obs, *_ = env.step(obs[column:column + 1])
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        obs, _, _, truncated, _ = env.step(obs[column:column + 1])
        if truncated:
            obs, _ = env.reset()
        n += 1
    return n / (time.perf_counter() - t0)


def vector_ticks_per_s(n_rigs: int, period_s: float, seconds: float, mode: str,
                       seed: int = 0, kwargs: dict | None = None) -> float:
    import gymnasium

    import drill_sim.gym
    envs = gymnasium.make_vec(drill_sim.gym.ENV_ID, num_envs=n_rigs, control_period_s=period_s,
                              top_drive_mode=mode, **(kwargs or {}))
    obs, _ = envs.reset(seed=seed)
    column = 1 if mode == "torque" else 4
    for _ in range(5):
        obs, *_ = envs.step(obs[:, column:column + 1])
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        obs, *_ = envs.step(obs[:, column:column + 1])
        steps += 1
    rate = steps * n_rigs / (time.perf_counter() - t0)
    envs.close()
    return rate


def _worker(args) -> float:
    return vector_ticks_per_s(*args)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="wall time per figure [s]")
    parser.add_argument("--period", type=float, default=0.01, help="control period [s]")
    parser.add_argument("--mode", choices=("torque", "speed"), default="torque")
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 16, 64, 256])
    parser.add_argument("--string-model", choices=("lumped", "distributed"), default="lumped")
    parser.add_argument("--sensor-profile", default="ideal")
    args = parser.parse_args()
    if not 0.2 <= args.seconds <= 600.0:
        parser.error(f"--seconds {args.seconds:g}: expected 0.2 to 600 s")
    if any(not 1 <= n <= 65_536 for n in args.sizes):
        parser.error(f"--sizes {args.sizes}: expected 1 to 65536 rigs each")
    cores = len(os.sched_getaffinity(0))
    kwargs = {"string_model": args.string_model, "sensor_profile": args.sensor_profile}
    ceiling = stepper_ticks_per_s(args.period, max(args.seconds, 2.0), args.string_model)
    single = single_env_ticks_per_s(args.period, args.seconds, args.mode, **kwargs)
    print(f"control period {args.period * 1e3:g} ms, {args.mode} mode, base, "
          f"{args.string_model} string, {args.sensor_profile} sensors; {cores} cores")
    print(f"compiled stepper (one rig, long advances): {ceiling:,.0f} rig-ticks/s")
    print(f"one RigEnv stepped from Python:            {single:,.0f} rig-ticks/s")
    print("rigs N | one core: rig-ticks/s | of the stepper | x one RigEnv | "
          f"{cores} cores: rig-ticks/s | x one core")
    ctx = multiprocessing.get_context("spawn")
    for n in args.sizes:
        one = vector_ticks_per_s(n, args.period, args.seconds, args.mode, 0, kwargs)
        per = max(1, n // cores)
        with ctx.Pool(cores) as pool:
            rates = pool.map(_worker, [(per, args.period, args.seconds, args.mode, 1000 * i,
                                        kwargs) for i in range(cores)])
        every = float(np.sum(rates))
        print(f"{n:6d} | {one:21,.0f} | {one / ceiling:13.0%} | {one / single:12.1f} | "
              f"{every:20,.0f} | {every / one:9.2f}")


if __name__ == "__main__":
    main()
