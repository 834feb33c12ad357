"""``drill_sim simulate``: run the model offline and summarise it, optionally as CSV, PNG, JSON."""

from __future__ import annotations

import argparse
import csv
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..core import RPM, ParameterError, Trajectory
from ..core.sensor_profile import CHANNELS, SensorProfile, load_profile
from ..core.sensors import SensorBank
from ..study.single import run_single
from ..terminal import Progress
from .case import Case, add_model_arguments, resolve_case
from .checks import in_range, json_line, number, output_file, plot_file, sensor_seed, typed
from .errors import UsageError
from .plot import plot_time_series
from .single import (
    Drive,
    add_run_arguments,
    amount,
    formations_note,
    resolve_drive,
    resolve_start,
    resolve_timing,
    run_settings,
)

SI_COLUMNS = ("time_s", "bit_speed_rad_s", "rop_m_s", "wob_n", "tob_nm", "surface_torque_nm",
              "depth_of_cut_m", "bit_depth_m", "top_drive_speed_rad_s", "stuck", "off_bottom",
              "top_drive_speed_setpoint_rad_s", "motor_torque_nm")
GROUP_COLUMNS = ("tau", "omega", "v", "w", "t", "ts", "delta_n", "u", "omega0", "stuck",
                 "off_bottom", "omega_td", "motor_torque")


# The documented limits (msg_docs/cli.md, "Limits"); the run's own are in cli/single.py.
MAX_ROWS = 1_000_000           # samples held for --out and --plot
BYTES_PER_ROW = 600            # held at the peak, all copies together (estimate)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_model_arguments(parser)
    add_run_arguments(parser, duration_default="60 s or 300 t*")
    parser.add_argument("--out", type=Path, help="CSV file of the time series")
    parser.add_argument("--output-interval", type=number, default=None,
                        help="CSV/plot sampling interval [s] or [t*]; default 0.01 s or 0.05 t*; "
                             f"at most {MAX_ROWS:,} samples")
    parser.add_argument("--plot", type=Path,
                        help="figure of bit speed, WOB and TOB against time (.png, .pdf, .svg...)")
    parser.add_argument("--json", action="store_true",
                        help="print the summary as one JSON object (strict: null, never NaN)")
    parser.add_argument("--sensor-profile", default=None,
                        help="SI mode, with --out: also write what the rig's sensors show, "
                             "measured_<channel> and fresh_<channel> columns, under this "
                             "sensor profile (ideal, surface_rig, mud_pulse, wired_pipe or a "
                             "profile YAML file), sampled on the CSV's rows")
    parser.add_argument("--sensor-seed", type=int, default=None,
                        help="seed of the sensors' noise, 0 to 2147483647; default 0")


def run(args: argparse.Namespace) -> int:
    case = resolve_case(args)
    timing = resolve_timing(args, case, 60.0, 300.0)
    unit, duration, dt = timing.unit, timing.duration, timing.dt
    interval = (0.01 if case.si else 0.05) if args.output_interval is None else in_range(
        "--output-interval", args.output_interval, 0.0, duration, unit=unit, low_open=True,
        what="a sampling interval within --duration")
    keep_rows = args.out is not None or args.plot is not None
    if keep_rows:
        _check_rows(args, duration, dt, interval, unit)
    if args.out is not None:
        output_file("--out", args.out)
    if args.plot is not None:
        plot_file("--plot", args.plot)
    sensors = _resolve_sensors(args, case)
    gap, perturbation = resolve_start(args, case)
    drive = resolve_drive(args, case)
    settings = run_settings(case, timing, args.start, gap, perturbation, drive=drive,
                            string_model=args.string_model)
    formations_note(case, "drill_sim simulate")

    progress = Progress("simulating")
    result = run_single(settings, output_interval=interval / timing.t_star_s if keep_rows
                        else None, progress=progress)   # None: keep no samples
    progress.close()
    summary = _summary(case, result.parts[-1], settings.start, duration, timing.window, dt,
                       drive)
    summary["string_model"] = settings.string_model
    if sensors is not None:
        summary.update(sensor_profile=sensors.name, sensor_seed=args.sensor_seed or 0)

    if keep_rows:
        columns = _columns(case, *result.parts)
        if sensors is not None:
            columns.update(_measured(case, sensors, args.sensor_seed or 0, interval, columns))
        if args.out is not None:
            _write_csv(args.out, columns)
        if args.plot is not None:
            _plot(args.plot, case, columns)
    if args.json:
        print(json_line(summary))
    else:
        _print_summary(summary, args)
    return 0


def _resolve_sensors(args: argparse.Namespace, case: Case) -> SensorProfile | None:
    """The sensor profile of --sensor-profile (None without it), checked with --sensor-seed."""
    if args.sensor_profile is None:
        if args.sensor_seed is not None:
            raise UsageError("--sensor-seed seeds the sensors' noise: expected "
                             "--sensor-profile too")
        return None
    if not case.si:
        raise UsageError("--sensor-profile measures SI quantities: expected SI mode "
                         "(--preset, --rpm, --wob-kn), not --groups")
    if args.out is None:
        raise UsageError("--sensor-profile adds measured columns to the CSV: expected --out")
    if args.sensor_seed is not None:
        sensor_seed(args.sensor_seed)
    try:
        return load_profile(args.sensor_profile)
    except ParameterError as exc:
        raise UsageError(f"--sensor-profile: {exc}") from None


def _measured(case: Case, profile: SensorProfile, seed: int, interval_s: float,
              columns: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """measured_<channel> and fresh_<channel> (0/1) columns: the sensors of ``profile`` read
    each CSV row as a tick (rows ``interval_s`` [s] apart; the hook load is the run's)."""
    exact = dict(columns)
    hook_n = case.preset.rig.submerged_weight_n - case.w0 * case.preset.rig.scales.force_n
    exact["hook_load_n"] = np.full(len(columns["time_s"]), hook_n)
    read = SensorBank(profile, interval_s, seed).measure_series(columns["time_s"], exact)
    out = {f"measured_{c}": read[c] for c in CHANNELS}
    out.update({f"fresh_{c}": read[f"fresh_{c}"].astype(int) for c in CHANNELS})
    return out


def _check_rows(args: argparse.Namespace, duration: float, dt: float, interval: float,
                unit: str) -> None:
    """Refuse a run whose samples for --out/--plot would not fit MAX_ROWS."""
    rows = duration / max(interval, dt)
    if rows > MAX_ROWS:
        given = (f"--output-interval {typed(args.output_interval)}"
                 if args.output_interval is not None else f"the default output interval "
                 f"{interval:g}")
        option = "--out" if args.out is not None else "--plot"
        raise UsageError(
            f"--duration {typed(duration)} {unit} at {given} {unit} would hold "
            f"{amount(rows)} samples (about {rows * BYTES_PER_ROW / 1e9:.3g} GB) for "
            f"{option}; expected at most {MAX_ROWS:,} samples: shorten --duration or raise "
            "--output-interval")


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
             dt: float, drive: Drive | None) -> dict:
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
            mean_top_drive_speed=si["mean_top_drive_speed_rad_s"],
            mean_motor_torque=si["mean_motor_torque_nm"],
            top_drive=(drive or Drive(case.preset.top_drive)).top_drive.as_dict(),
            units={"time": "s", "mean_bit_speed": "rad/s", "max_bit_speed": "rad/s",
                   "top_drive_speed": "rad/s", "mean_wob": "N", "available_weight": "N",
                   "mean_tob": "N m", "mean_surface_torque": "N m", "mean_rop": "m/s",
                   "mean_top_drive_speed": "rad/s", "mean_motor_torque": "N m"})
        if drive is not None and drive.motor_torque_nm is not None:
            summary["motor_torque_command"] = drive.motor_torque_nm
            summary["units"]["motor_torque_command"] = "N m"
    else:
        summary.update(
            ssi=m.ssi, stick_fraction=m.stick_fraction, bounce_fraction=m.bounce_fraction,
            mean_bit_speed=m.mean_bit_speed, mean_wob=m.mean_wob, mean_tob=m.mean_tob,
            mean_surface_torque=m.mean_surface_torque, mean_rop=m.mean_rop,
            max_bit_speed=m.max_bit_speed, omega0=case.omega0, w0=case.w0,
            mean_top_drive_speed=m.mean_top_drive_speed, mean_motor_torque=m.mean_motor_torque,
            top_drive={"top_drive_mode": "kinematic"},
            units={"time": "t*", "mean_bit_speed": "1/t*", "mean_wob": "F*", "mean_tob": "C",
                   "mean_surface_torque": "C", "mean_rop": "L*/t*",
                   "mean_top_drive_speed": "1/t*", "mean_motor_torque": "C"})
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
             f"{s['duration']:g} {u['time']} at dt = {s['dt']:.3g} {u['time']}, "
             f"{s['string_model']} string",
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
        mode = s["top_drive"]["top_drive_mode"]
        if mode != "kinematic":
            lines += [f"  top drive            {s['mean_top_drive_speed'] / RPM:10.2f} rpm "
                      f"({mode} mode), motor torque {s['mean_motor_torque'] / 1e3:.3f} kN m"]
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
