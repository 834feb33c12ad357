"""Speed of ``drill_sim map``: throughput per core against the stepper, two workers against one,
and a local Dask cluster against the built-in pool, on the base map of 30 x 30 points
(20-300 rpm x 50-250 kN) with 120 s simulated per point at the default dt.

Prints (issue targets in brackets):
  - the stepper's own steps per second (bench_core's figure: base preset in stick-slip) and
    the bare stepper on the map's own points (a sample of them, every 10th);
  - the map with one worker, in steps per second per core, against both [>= 90 %];
  - the map with two workers against one [>= 1.8 x], and its wall time;
  - the map on a local Dask cluster of two single-threaded worker processes (started before the
    clock starts, as an existing cluster would be) against the built-in pool [within 15 %].

Each map is run through the command itself (CSV written, rows appended as points finish), in a
fresh output folder. ``--size N`` runs an N x N grid over the same ranges, for a quicker look:
the figures per point are alike, the wall times scale with the points run.

Run: .venv/bin/python benchmarks/bench_map.py [--size 12]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import tempfile
import time

from bench_core import steps_per_second

from drill_sim.cli.main import build_parser, main
from drill_sim.cli.map_grid import build_grid
from drill_sim.cli.single import resolve_start, resolve_timing, run_settings
from drill_sim.core import Simulator


def grid_args(size: int) -> list[str]:
    """The base map's arguments on a ``size`` x ``size`` grid, 120 s a point."""
    return ["--rpm", f"20:300:{size}", "--wob-kn", f"50:250:{size}", "--duration", "120"]


def points(argv: list[str]) -> list:
    """The map's points, as the command builds them."""
    args = build_parser().parse_args(["map", *argv])
    grid = build_grid(args)
    timing = resolve_timing(args, grid.case(0), 60.0, 300.0)
    gap, perturbation = resolve_start(args, grid.case(0))
    return [run_settings(grid.case(p), timing, None, gap, perturbation)
            for p in range(grid.size)]


class Clock:
    """Wall and CPU seconds of this process between ``start`` and ``stop``."""

    def __enter__(self) -> Clock:
        self.wall, self.cpu = time.perf_counter(), time.process_time()
        return self

    def __exit__(self, *exc) -> None:
        self.wall = time.perf_counter() - self.wall
        self.cpu = time.process_time() - self.cpu


def stepper_cpu_rate(steps: int = 20_000_000, repeats: int = 3) -> float:
    """bench_core's stepper measurement in steps per CPU second (robust to a busy machine)."""
    from drill_sim.core import Rig, load_preset
    preset = load_preset("base")
    rig = Rig(preset.rig)
    rig.start_steady(preset.top_drive_speed_rad_s, preset.hook_load_n, 1e-3)
    rig.advance(30.0)
    best = float("inf")
    for _ in range(repeats):
        with Clock() as c:
            rig.advance_steps(steps)
        best = min(best, c.cpu)
    return steps / best


def bare_rates(settings: list) -> tuple[float, float]:
    """Steps per wall second and per CPU second of the stepper alone on these points."""
    steps, wall, cpu = 0, 0.0, 0.0
    for s in settings:
        sim = Simulator(s.groups, s.dt)
        if s.start == "steady":
            sim.start_steady(s.w0, s.omega0, s.perturbation)
        else:
            sim.start_at_rest(s.gap)
            sim.set_commands(s.w0, s.omega0)
        with Clock() as c:
            sim.advance(s.steps)
        steps, wall, cpu = steps + s.steps, wall + c.wall, cpu + c.cpu
    return steps / wall, steps / cpu


def timed_map(argv: list[str], extra: list[str]) -> Clock:
    """Run the map through the command in a fresh folder; its summary is not printed."""
    with tempfile.TemporaryDirectory() as folder, Clock() as clock:
        with contextlib.redirect_stdout(io.StringIO()):
            status = main(["map", *argv, *extra, "--out", os.path.join(folder, "m.csv")])
    assert status == 0
    return clock


def main_bench() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--size", type=int, default=30, help="points per axis (default 30)")
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f} (1 min), "
          f"{os.getloadavg()[1]:.2f} (5 min); cores: {len(os.sched_getaffinity(0))}")
    stepper, _, _ = steps_per_second(steps=20_000_000, repeats=3)
    stepper_cpu = stepper_cpu_rate()
    argv = grid_args(args.size)
    settings = points(argv)
    steps = sum(s.steps for s in settings)
    bare, bare_cpu = bare_rates(settings[::10])
    print(f"stepper (bench_core, stick-slip): {stepper / 1e6:.1f} M steps/s wall, "
          f"{stepper_cpu / 1e6:.1f} M per CPU s; on every 10th of the map's {len(settings)} "
          f"points: {bare / 1e6:.1f} M steps/s wall, {bare_cpu / 1e6:.1f} M per CPU s")

    one = timed_map(argv, ["--workers", "1"])
    wall, cpu = steps / one.wall, steps / one.cpu
    print(f"map, 1 worker: {steps / 1e9:.3f} G steps in {one.wall:.1f} s wall "
          f"({one.cpu:.1f} CPU s): {wall / 1e6:.1f} M steps/s = {100 * wall / stepper:.0f} % of "
          f"the stepper's (bench_core), {100 * wall / bare:.0f} % of the bare stepper's on the "
          f"map's points; per CPU s {100 * cpu / stepper_cpu:.0f} % and {100 * cpu / bare_cpu:.0f}"
          " % [>= 90 %]")
    two = timed_map(argv, ["--workers", "2"])
    print(f"map, 2 workers: {two.wall:.1f} s wall, {one.wall / two.wall:.2f} x one worker "
          "[>= 1.8 x]")

    from distributed import LocalCluster
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=":0") as cluster:
        timed_map(["--rpm", "60", "--wob-kn", "100,120", "--duration", "1"],
                  ["--scheduler", cluster.scheduler_address])      # workers load the kernel
        dask = timed_map(argv, ["--scheduler", cluster.scheduler_address])
    print(f"map, local Dask cluster (2 worker processes): {dask.wall:.1f} s wall, "
          f"{100 * (dask.wall / two.wall - 1):+.0f} % against the built-in pool [within 15 %]")
    print(f"load average after: {os.getloadavg()[0]:.2f} (1 min)")


if __name__ == "__main__":
    main_bench()
