"""``drill_sim simulate``: run the model offline and summarise it, optionally as CSV, PNG, JSON."""

from __future__ import annotations

import argparse
import csv
import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..core import DEFAULT_DT, RPM, NoSteadyDrilling, Simulator, Trajectory
from ..terminal import Progress
from .case import Case, add_model_arguments, finite, positive, resolve_case
from .errors import UsageError
from .plot import plot_time_series

SI_COLUMNS = ("time_s", "bit_speed_rad_s", "rop_m_s", "wob_n", "tob_nm", "surface_torque_nm",
              "depth_of_cut_m", "bit_depth_m", "top_drive_speed_rad_s", "stuck", "off_bottom")
GROUP_COLUMNS = ("tau", "omega", "v", "w", "t", "ts", "delta_n", "u", "omega0", "stuck",
                 "off_bottom")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_model_arguments(parser)
    parser.add_argument("--duration", type=float, default=None,
                        help="simulated time [s] (SI) or [t*] (groups); default 60 s or 300 t*")
    parser.add_argument("--dt", type=float, default=None,
                        help=f"fixed step [s] or [t*]; default {DEFAULT_DT:g} t*")
    parser.add_argument("--start", choices=("steady", "rest"), default=None,
                        help="exact steady drilling (default when it exists) or bit at rest")
    parser.add_argument("--gap", type=float, default=0.0,
                        help="with --start rest: height of the bit above bottom [m] or [L*]")
    parser.add_argument("--perturbation", type=float, default=1e-3,
                        help="relative perturbation of the initial bit speed (steady start)")
    parser.add_argument("--out", type=Path, help="CSV file of the time series")
    parser.add_argument("--output-interval", type=float, default=None,
                        help="CSV/plot sampling interval [s] or [t*]; default 0.01 s or 0.05 t*")
    parser.add_argument("--metrics-window", type=float, default=None,
                        help="metrics over the last this much time [s] or [t*]; default: last "
                             "half")
    parser.add_argument("--plot", type=Path, help="PNG of bit speed, WOB and TOB against time")
    parser.add_argument("--json", action="store_true",
                        help="print the summary as one JSON object")


def run(args: argparse.Namespace) -> int:
    case = resolve_case(args)
    t_star = case.preset.rig.scales.time_s if case.si else 1.0   # user time unit -> t*
    duration = positive("--duration", args.duration, 60.0 if case.si else 300.0) / t_star
    dt = positive("--dt", args.dt, DEFAULT_DT * t_star) / t_star
    interval = positive("--output-interval", args.output_interval,
                        0.01 if case.si else 0.05) / t_star
    window = positive("--metrics-window", args.metrics_window, 0.5 * duration * t_star) / t_star
    if window > duration:
        raise UsageError(f"--metrics-window = {window * t_star:g} is longer than --duration")
    for path in (args.out, args.plot):
        if path is not None and not path.parent.exists():
            raise UsageError(f"cannot write {path}: folder {path.parent} does not exist")
    gap = finite("--gap", args.gap)
    if gap < 0:
        raise UsageError(f"--gap = {gap:g} is negative; expected a height >= 0")

    sim = Simulator(case.groups, dt)
    start = args.start or ("steady" if case.w0 > case.groups.lam else "rest")
    if start == "steady":
        try:
            sim.start_steady(case.w0, case.omega0, args.perturbation)
        except NoSteadyDrilling as exc:
            raise UsageError(f"--start steady: {exc}") from None
    else:
        sim.start_at_rest(gap / case.preset.rig.scales.length_m if case.si else gap)
        sim.set_commands(case.w0, case.omega0)

    progress = Progress("simulating")
    first = sim.run(duration - window, output_interval=interval,
                    progress=lambda f: progress(f * (1 - window / duration)))
    sim.reset_window()
    second = sim.run(window, output_interval=interval,
                     progress=lambda f: progress(1 - window / duration * (1 - f)))
    progress.close()
    columns = _columns(case, first, second)
    summary = _summary(case, second, start, duration * t_star, window * t_star, dt * t_star)

    if args.out is not None:
        _write_csv(args.out, columns)
    if args.plot is not None:
        _plot(args.plot, case, columns)
    if args.json:
        print(json.dumps(summary))
    else:
        _print_summary(summary, args)
    return 0


def _columns(case: Case, *parts: Trajectory) -> dict[str, np.ndarray]:
    """The CSV's columns over the runs ``parts``, in order: SI or dimensionless."""
    runs: Sequence[object] = parts
    names = GROUP_COLUMNS
    if case.si:
        runs = [p.to_si(case.preset.rig.scales, case.groups.n) for p in parts]
        names = SI_COLUMNS
    cols = {name: np.concatenate([getattr(r, name) for r in runs]) for name in names}
    cols["stuck"] = cols["stuck"].astype(int)
    cols["off_bottom"] = cols["off_bottom"].astype(int)
    return cols


def _summary(case: Case, run: Trajectory, start: str, duration: float, window: float,
             dt: float) -> dict:
    m = run.metrics
    summary: dict = {"mode": "si" if case.si else "dimensionless", "start": start,
                     "duration": duration, "dt": dt,
                     "metrics_window": [duration - window, duration]}
    if case.si:
        sc = case.preset.rig.scales
        si = m.to_si(sc)
        summary.update(
            preset=case.preset.name,
            ssi=si["ssi"], stick_fraction=si["stick_fraction"],
            bounce_fraction=si["bounce_fraction"],
            mean_bit_speed=si["mean_bit_speed_rad_s"], mean_wob=si["mean_wob_n"],
            mean_tob=si["mean_tob_nm"], mean_surface_torque=si["mean_surface_torque_nm"],
            mean_rop=si["mean_rop_m_s"], max_bit_speed=si["max_bit_speed_rad_s"],
            top_drive_speed=case.omega0 / sc.time_s, available_weight=case.w0 * sc.force_n,
            units={"time": "s", "mean_bit_speed": "rad/s", "max_bit_speed": "rad/s",
                   "top_drive_speed": "rad/s", "mean_wob": "N", "available_weight": "N",
                   "mean_tob": "N m", "mean_surface_torque": "N m", "mean_rop": "m/s"})
    else:
        summary.update(
            ssi=m.ssi, stick_fraction=m.stick_fraction, bounce_fraction=m.bounce_fraction,
            mean_bit_speed=m.mean_bit_speed, mean_wob=m.mean_wob, mean_tob=m.mean_tob,
            mean_surface_torque=m.mean_surface_torque, mean_rop=m.mean_rop,
            max_bit_speed=m.max_bit_speed, omega0=case.omega0, w0=case.w0,
            units={"time": "t*", "mean_bit_speed": "1/t*", "mean_wob": "F*", "mean_tob": "C",
                   "mean_surface_torque": "C", "mean_rop": "L*/t*"})
    summary["groups"] = {"n": case.groups.n, "psi": case.groups.psi, "lambda": case.groups.lam,
                         "beta": case.groups.beta}
    return {k: (float(v) if isinstance(v, (np.floating, float)) else v)
            for k, v in summary.items()}


def _write_csv(path: Path, columns: dict[str, np.ndarray]) -> None:
    names = list(columns)
    data = np.column_stack([columns[n] for n in names])
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(names)
        for row in data:
            writer.writerow([f"{v:.9g}" for v in row])


def _plot(path: Path, case: Case, cols: dict[str, np.ndarray]) -> None:
    if case.si:
        plot_time_series(path, cols["time_s"], cols["bit_speed_rad_s"] / RPM,
                         cols["top_drive_speed_rad_s"] / RPM, cols["wob_n"] / 1e3,
                         cols["tob_nm"] / 1e3, cols["surface_torque_nm"] / 1e3,
                         cols["stuck"].astype(bool),
                         units={"time": "s", "speed": "rpm", "force": "kN", "torque": "kN m"},
                         title=f"drill_sim, preset {case.preset.name}")
    else:
        plot_time_series(path, cols["tau"], cols["omega"], cols["omega0"], cols["w"], cols["t"],
                         cols["ts"], cols["stuck"].astype(bool),
                         units={"time": "t*", "speed": "1/t*", "force": "F*", "torque": "C"},
                         title=f"drill_sim, {case.groups}")


def _print_summary(s: dict, args: argparse.Namespace) -> None:
    u = s["units"]
    lines = [f"drill_sim simulate: {s.get('preset', 'groups')} ({s['mode']}), start {s['start']}, "
             f"{s['duration']:g} {u['time']} at dt = {s['dt']:.3g} {u['time']}",
             f"metrics over {s['metrics_window'][0]:g}..{s['metrics_window'][1]:g} {u['time']}:"]
    if s["mode"] == "si":
        lines += [
            f"  mean bit speed       {s['mean_bit_speed'] / RPM:10.2f} rpm "
            f"(top drive {s['top_drive_speed'] / RPM:.2f} rpm, max {s['max_bit_speed'] / RPM:.1f})",
            f"  mean WOB             {s['mean_wob'] / 1e3:10.2f} kN  (W0 "
            f"{s['available_weight'] / 1e3:.2f} kN)",
            f"  mean TOB             {s['mean_tob'] / 1e3:10.3f} kN m",
            f"  mean surface torque  {s['mean_surface_torque'] / 1e3:10.3f} kN m",
            f"  mean ROP             {s['mean_rop'] * 3600:10.2f} m/h"]
    else:
        lines += [f"  mean {k:<20} {s[k]:10.4g} {u[k]}" for k in
                  ("mean_bit_speed", "mean_wob", "mean_tob", "mean_surface_torque", "mean_rop")]
    lines += [f"  SSI                  {s['ssi']:10.3f}",
              f"  stick fraction       {s['stick_fraction']:10.3f}",
              f"  bounce fraction      {s['bounce_fraction']:10.3f}"]
    for label, path in (("CSV", args.out), ("plot", args.plot)):
        if path is not None:
            lines.append(f"{label} written to {path}")
    print("\n".join(lines))
