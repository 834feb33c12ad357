"""``drill_sim run``: the main job. The rig node and a scenario driver in subprocesses, a live
status line, and at the end a summary and a plot."""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from ..core import RPM, load_preset
from ..core.scenario import load_scenario
from .errors import UsageError


def executable(name: str) -> str:
    beside = Path(sys.executable).parent / name
    found = str(beside) if beside.exists() else shutil.which(name)
    if found is None:
        raise OSError(f"{name} is not installed (pip install the package first)")
    return found


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--scenario", default="tag_bottom", help="shipped scenario or YAML file")
    p.add_argument("--preset", default="base", help="rig preset or preset YAML file")
    p.add_argument("--duration", type=float, default=None,
                   help="wall seconds to run; default: the scenario's duration")
    p.add_argument("--plot", type=Path, default=Path("drill_sim.png"),
                   help="PNG written at the end")
    p.add_argument("--ros-args", dest="ros_args", nargs=argparse.REMAINDER, default=[],
                   help="passed on to drill_sim_node (e.g. -p rate_hz:=500.0)")


def run_session(args: argparse.Namespace) -> int:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from ..ros.monitor import Monitor
    from .plot import plot_time_series

    scenario = load_scenario(args.scenario)
    preset = load_preset(args.preset)
    duration = scenario.duration_s if args.duration is None else args.duration
    if not 0 < duration < 1e6:
        raise UsageError(f"--duration = {duration:g}: expected a positive number of seconds")
    if not args.plot.parent.exists():
        raise UsageError(f"cannot write {args.plot}: folder {args.plot.parent} does not exist")
    node_cmd = [executable("drill_sim_node"), "--ros-args", "-p", f"preset:={args.preset}",
                "-p", f"initial_state:={scenario.initial_state}", *args.ros_args]
    drive_cmd = [executable("drill_sim_drive"), args.scenario]
    env = dict(os.environ)
    procs = [subprocess.Popen(node_cmd, env=env), subprocess.Popen(drive_cmd, env=env)]
    rclpy.init()
    monitor = Monitor()
    executor = SingleThreadedExecutor()
    executor.add_node(monitor)
    tty = sys.stdout.isatty()
    try:
        start = time.monotonic()
        last_print = 0.0
        while time.monotonic() - start < duration + 2.0:
            executor.spin_once(timeout_sec=0.02)
            if any(p.poll() is not None for p in procs[:1]):
                raise RuntimeError("drill_sim_node exited early")
            now = time.monotonic()
            if now - last_print > (0.2 if tty else 5.0):
                last_print = now
                s = monitor.latest()
                if s is not None:
                    line = (f"t {s['time_s'] - monitor.samples()[0, 0]:6.1f} s | bit "
                            f"{s['bit_speed_rad_s'] / RPM:6.1f} rpm (top drive "
                            f"{s['top_drive_speed_rad_s'] / RPM:5.1f}) | WOB "
                            f"{s['wob_n'] / 1e3:6.1f} kN | TOB {s['tob_nm'] / 1e3:5.2f} kN m | "
                            f"{'STICK-SLIP' if s['stick_slip'] else 'smooth    '}")
                    print(("\r" + line) if tty else line, end="" if tty else "\n", flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        if tty:
            print()
        for p in procs:
            if p.poll() is None:
                p.send_signal(signal.SIGINT)
        for p in procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
        data = monitor.samples().copy()
        executor.shutdown()
        monitor.destroy_node()
        rclpy.try_shutdown()
    if data.shape[0] < 2:
        print("drill_sim run: no samples received from the rig", file=sys.stderr)
        return 1
    t = data[:, 0] - data[0, 0]
    last = t >= t[-1] - min(20.0, t[-1] / 2)
    speed = data[:, 2]
    print(f"drill_sim run: scenario '{scenario.name}' on preset '{preset.name}', "
          f"{t[-1]:.1f} s simulated, {data.shape[0]} samples")
    print(f"  hole drilled             {data[-1, 8]:8.3f} m")
    print(f"  last {t[-1] - t[last][0]:4.1f} s: mean bit speed "
          f"{speed[last].mean() / RPM:6.1f} rpm, WOB {data[last, 4].mean() / 1e3:6.1f} kN, "
          f"TOB {data[last, 5].mean() / 1e3:5.2f} kN m")
    print(f"  stick fraction (whole run)  {np.mean(speed == 0.0):.3f}; "
          f"stick-slip flagged {np.mean(data[:, 9] > 0):.3f} of the time")
    plot_time_series(args.plot, t, speed / RPM, data[:, 1] / RPM, data[:, 4] / 1e3,
                     data[:, 5] / 1e3, data[:, 6] / 1e3, speed == 0.0,
                     units={"time": "s", "speed": "rpm", "force": "kN", "torque": "kN m"},
                     title=f"drill_sim run: {scenario.name} on {preset.name}")
    print(f"plot written to {args.plot}")
    return 0
