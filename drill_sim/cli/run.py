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
from datetime import datetime
from pathlib import Path

import numpy as np

from ..core import RPM, load_preset
from ..core.scenario import load_scenario
from .checks import in_range, new_bag, number, plot_file
from .errors import UsageError

MAX_DURATION_S = 1e6     # --duration [s] (documented in msg_docs/cli.md, "Limits")


def executable(name: str) -> str:
    beside = Path(sys.executable).parent / name
    found = str(beside) if beside.exists() else shutil.which(name)
    if found is None:
        raise OSError(f"{name} is not installed (pip install the package first)")
    return found


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scenario", default="tag_bottom", help="shipped scenario or YAML file")
    parser.add_argument("--preset", default="base", help="rig preset or preset YAML file")
    parser.add_argument("--duration", type=number, default=None,
                        help=f"wall seconds to run, up to {MAX_DURATION_S:g}; default: the "
                             "scenario's duration")
    parser.add_argument("--plot", type=Path, default=Path("drill_sim.png"),
                        help="figure written at the end (.png, .pdf, .svg...)")
    parser.add_argument("--record", type=Path, default=None, metavar="BAG",
                        help="bag directory to record the session into (default: "
                             "drill_sim_session_<date>-<time> here)")
    parser.add_argument("--no-record", action="store_true", help="do not record the session")
    parser.add_argument("--ros-args", dest="ros_args", nargs=argparse.REMAINDER, default=[],
                        help="passed on to drill_sim_node (e.g. -p rate_hz:=500.0)")


def run(args: argparse.Namespace) -> int:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from ..ros.monitor import Monitor
    from .plot import plot_rig_series

    if args.no_record and args.record is not None:
        raise UsageError(f"--no-record with --record {args.record}: they contradict each other; "
                         "expected one of them")
    scenario = load_scenario(args.scenario)
    preset = load_preset(args.preset)
    duration = scenario.duration_s if args.duration is None else in_range(
        "--duration", args.duration, 0.0, MAX_DURATION_S, unit="s", low_open=True,
        what="a wall time")
    plot_file("--plot", args.plot)
    if args.no_record:
        bag = None
    elif args.record is not None:
        bag = new_bag("--record", args.record)
    else:
        bag = new_bag("--record", Path(datetime.now().strftime(
            "drill_sim_session_%Y_%m_%d-%H_%M_%S")))
    node_cmd = [executable("drill_sim_node"), "--ros-args", "-p", f"preset:={args.preset}",
                "-p", f"initial_state:={scenario.initial_state}",
                *(("-p", f"record:={bag.absolute()}") if bag is not None else ()),
                *args.ros_args]
    drive_cmd = [executable("drill_sim_drive"), args.scenario]
    env = dict(os.environ)
    procs = [subprocess.Popen(node_cmd, env=env), subprocess.Popen(drive_cmd, env=env)]
    rclpy.init()
    monitor = Monitor()
    executor = SingleThreadedExecutor()
    executor.add_node(monitor)
    tty = sys.stdout.isatty()
    node_exit = None
    try:
        start = time.monotonic()
        last_print = 0.0
        while time.monotonic() - start < duration + 2.0:
            executor.spin_once(timeout_sec=0.02)
            node_exit = procs[0].poll()
            if node_exit is not None:
                break
            now = time.monotonic()
            if now - last_print > (0.2 if tty else 5.0):
                last_print = now
                s = monitor.latest()
                if s is not None:
                    line = (f"t {s['elapsed_s']:6.1f} s | bit "
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
        series, flags = monitor.series(), monitor.flags()
        executor.shutdown()
        monitor.destroy_node()
        rclpy.try_shutdown()
    if node_exit is not None:
        print(f"drill_sim run: drill_sim_node stopped early with status {node_exit} "
              "(its message is above)", file=sys.stderr)
        return 1
    if series.time_s.size < 2:
        print("drill_sim run: no samples received from the rig", file=sys.stderr)
        return 1
    elapsed = series.time_s[-1] - series.time_s[0]
    whole = series.metrics()
    last = series.window(elapsed - min(20.0, elapsed / 2), None).metrics()
    print(f"drill_sim run: scenario '{scenario.name}' on preset '{preset.name}', "
          f"{elapsed:.1f} s simulated, {whole['samples']} samples")
    print(f"  hole drilled             {series.hole_depth_m[-1]:8.3f} m")
    print(f"  last {last['duration_s']:4.1f} s: mean bit speed "
          f"{last['mean_bit_speed_rad_s'] / RPM:6.1f} rpm, WOB {last['mean_wob_n'] / 1e3:6.1f} kN, "
          f"TOB {last['mean_tob_nm'] / 1e3:5.2f} kN m")
    print(f"  stick fraction (whole run)  {whole['stick_fraction']:.3f}; "
          f"stick-slip flagged {np.mean(flags):.3f} of the time")
    plot_rig_series(args.plot, series, title=f"drill_sim run: {scenario.name} on {preset.name}")
    print(f"plot written to {args.plot}")
    if bag is not None and bag.is_dir():
        print(f"session recorded to {bag}: replay it with drill_sim_replay, re-run it with "
              f"drill_sim bag resim, or see drill_sim bag info|metrics|plot")
    return 0
