"""``drill_sim``: offline simulation and stability analysis from a terminal.

Two modes share every subcommand: SI (``--preset`` with ``--rpm`` and ``--wob-kn`` or
``--hook-load-kn``, times in seconds) and dimensionless (``--groups`` with ``--w0`` and
``--omega0``, times in units of t*). Bad arguments exit with status 2 and one line on stderr.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core import (
    RPM,
    Groups,
    NoSteadyDrilling,
    ParameterError,
    Preset,
    Simulator,
    load_preset,
    preset_names,
    stability,
    steady_state,
)
from ..core.simulator import DEFAULT_DT, Trajectory
from . import bag as bag_cli
from .errors import UsageError
from .plot import plot_time_series
from .progress import Progress
from .run import add_arguments, run_session

SI_COLUMNS = ("time_s", "bit_speed_rad_s", "rop_m_s", "wob_n", "tob_nm", "surface_torque_nm",
              "depth_of_cut_m", "bit_depth_m", "top_drive_speed_rad_s", "stuck", "off_bottom")
GROUP_COLUMNS = ("tau", "omega", "v", "w", "t", "ts", "delta_n", "u", "omega0", "stuck",
                 "off_bottom")
SUMMARY_KEYS = ("ssi", "stick_fraction", "bounce_fraction", "mean_bit_speed", "mean_wob",
                "mean_tob", "mean_surface_torque", "mean_rop")


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one clear line, never a usage dump
        raise UsageError(message)


@dataclass(frozen=True)
class Case:
    """What to simulate, resolved from the arguments: groups, commands and unit scales."""

    groups: Groups
    w0: float
    omega0: float
    preset: Preset | None      # None in dimensionless mode

    @property
    def si(self) -> bool:
        return self.preset is not None


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="drill_sim", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    def model_args(p: argparse.ArgumentParser) -> None:
        g = p.add_argument_group("SI mode")
        g.add_argument("--preset", default=None,
                       help=f"shipped preset ({', '.join(preset_names())}) or preset YAML file; "
                            "default base")
        g.add_argument("--rpm", type=float, help="top-drive speed [rpm]; default: the preset's")
        load = g.add_mutually_exclusive_group()
        load.add_argument("--wob-kn", type=float,
                          help="available weight on bit W0 = W_s - H0 [kN]; default: the preset's")
        load.add_argument("--hook-load-kn", type=float, help="hook load H0 [kN]")
        d = p.add_argument_group("dimensionless mode")
        d.add_argument("--groups", help="n=4,psi=13.73,lambda=6.84,beta=0.36")
        d.add_argument("--w0", type=float, help="available weight W0/F* [-]")
        d.add_argument("--omega0", type=float, help="top-drive speed Omega0 t* [-]")

    sim = sub.add_parser("simulate", help="run the model offline and summarise it")
    model_args(sim)
    sim.add_argument("--duration", type=float, default=None,
                     help="simulated time [s] (SI) or [t*] (groups); default 60 s or 300 t*")
    sim.add_argument("--dt", type=float, default=None,
                     help=f"fixed step [s] or [t*]; default {DEFAULT_DT:g} t*")
    sim.add_argument("--start", choices=("steady", "rest"), default=None,
                     help="exact steady drilling (default when it exists) or bit at rest")
    sim.add_argument("--gap", type=float, default=0.0,
                     help="with --start rest: height of the bit above bottom [m] or [L*]")
    sim.add_argument("--perturbation", type=float, default=1e-3,
                     help="relative perturbation of the initial bit speed (steady start)")
    sim.add_argument("--out", type=Path, help="CSV file of the time series")
    sim.add_argument("--output-interval", type=float, default=None,
                     help="CSV/plot sampling interval [s] or [t*]; default 0.01 s or 0.05 t*")
    sim.add_argument("--metrics-window", type=float, default=None,
                     help="metrics over the last this much time [s] or [t*]; default: last half")
    sim.add_argument("--plot", type=Path, help="PNG of bit speed, WOB and TOB against time")
    sim.add_argument("--json", action="store_true", help="print the summary as one JSON object")

    run = sub.add_parser("run", help="the main job: rig node + scenario driver, live status, "
                                     "summary and plot")
    add_arguments(run)

    bag_cli.add_arguments(sub.add_parser("bag", help=bag_cli.HELP))

    stab = sub.add_parser("stability", help="steady drilling and the rightmost roots of Delta(s)")
    model_args(stab)
    stab.add_argument("--re-min", type=float, default=-0.5,
                      help="find every root with Re s >= this [1/t*] (negative)")
    stab.add_argument("--count", type=int, default=8, help="how many roots to print")
    stab.add_argument("--json", action="store_true", help="print the result as one JSON object")
    return parser


def parse_groups(text: str) -> Groups:
    values: dict[str, str] = {}
    for item in text.split(","):
        key, sep, value = item.partition("=")
        if not sep:
            raise UsageError(f"--groups: {item!r} is not key=value; expected "
                             "n=...,psi=...,lambda=...,beta=...")
        values[key.strip()] = value.strip()
    expected = {"n", "psi", "lambda", "beta"}
    if set(values) != expected:
        raise UsageError(f"--groups: got keys {sorted(values)}, expected exactly "
                         "n, psi, lambda, beta")
    try:
        numbers = {k: float(v) for k, v in values.items()}
    except ValueError as exc:
        raise UsageError(f"--groups: {exc}") from None
    return Groups(n=numbers["n"], psi=numbers["psi"], lam=numbers["lambda"], beta=numbers["beta"])


def resolve_case(args: argparse.Namespace) -> Case:
    if args.groups is not None:
        si_given = [o for o in ("preset", "rpm", "wob_kn", "hook_load_kn")
                    if getattr(args, o) is not None]
        if si_given:
            raise UsageError(f"--groups cannot be combined with --{si_given[0].replace('_', '-')}")
        if args.w0 is None or args.omega0 is None:
            raise UsageError("--groups needs --w0 and --omega0")
        groups = parse_groups(args.groups)
        return Case(groups, _finite("--w0", args.w0), _finite("--omega0", args.omega0), None)
    if args.w0 is not None or args.omega0 is not None:
        raise UsageError("--w0 and --omega0 go with --groups; in SI mode use --rpm and --wob-kn")
    preset = load_preset(args.preset or "base")
    rig = preset.rig
    rpm = preset.top_drive_speed_rpm if args.rpm is None else _finite("--rpm", args.rpm)
    if rpm < 0:
        raise UsageError(f"--rpm = {rpm:g} is negative; expected a top-drive speed >= 0 rpm")
    if args.hook_load_kn is not None:
        hook_n = 1e3 * _finite("--hook-load-kn", args.hook_load_kn)
        if hook_n < 0:
            raise UsageError(f"--hook-load-kn = {args.hook_load_kn:g} is negative; expected >= 0")
    else:
        wob_kn = preset.weight_on_bit_kn if args.wob_kn is None else _finite("--wob-kn",
                                                                             args.wob_kn)
        hook_n = rig.submerged_weight_n - 1e3 * wob_kn
        if hook_n < 0:
            raise UsageError(f"--wob-kn = {wob_kn:g} exceeds the string's submerged weight "
                             f"{rig.submerged_weight_n / 1e3:.1f} kN")
    sc = rig.scales
    w0 = (rig.submerged_weight_n - hook_n) / sc.force_n
    return Case(rig.groups, w0, rpm * RPM * sc.time_s, preset)


def _finite(name: str, value: float) -> float:
    if not math.isfinite(value):
        raise UsageError(f"{name} = {value} is not finite; expected a finite number")
    return value


def _positive(name: str, value: float | None, default: float) -> float:
    if value is None:
        return default
    if not math.isfinite(value) or value <= 0:
        raise UsageError(f"{name} = {value} is out of range; expected a finite number > 0")
    return value


def cmd_simulate(args: argparse.Namespace) -> int:
    case = resolve_case(args)
    t_star = case.preset.rig.scales.time_s if case.si else 1.0   # user time unit -> t*
    duration = _positive("--duration", args.duration, 60.0 if case.si else 300.0) / t_star
    dt = _positive("--dt", args.dt, DEFAULT_DT * t_star) / t_star
    interval = _positive("--output-interval", args.output_interval,
                         0.01 if case.si else 0.05) / t_star
    window = _positive("--metrics-window", args.metrics_window, 0.5 * duration * t_star) / t_star
    if window > duration:
        raise UsageError(f"--metrics-window = {window * t_star:g} is longer than --duration")
    for path in (args.out, args.plot):
        if path is not None and not path.parent.exists():
            raise UsageError(f"cannot write {path}: folder {path.parent} does not exist")
    gap = _finite("--gap", args.gap)
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
    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name) for p in parts])

    if not case.si:
        cols = {name: cat(name) for name in GROUP_COLUMNS if name not in ("stuck", "off_bottom")}
    else:
        sc = case.preset.rig.scales
        cols = {
            "time_s": cat("tau") * sc.time_s,
            "bit_speed_rad_s": cat("omega") / sc.time_s,
            "rop_m_s": cat("v") * sc.velocity_m_s,
            "wob_n": cat("w") * sc.force_n,
            "tob_nm": cat("t") * sc.stiffness_nm_per_rad,
            "surface_torque_nm": cat("ts") * sc.stiffness_nm_per_rad,
            "depth_of_cut_m": cat("delta_n") * case.groups.n * sc.length_m,
            "bit_depth_m": cat("u") * sc.length_m,
            "top_drive_speed_rad_s": cat("omega0") / sc.time_s,
        }
    cols["stuck"] = cat("stuck").astype(int)
    cols["off_bottom"] = cat("off_bottom").astype(int)
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


def cmd_stability(args: argparse.Namespace) -> int:
    case = resolve_case(args)
    if args.count < 1:
        raise UsageError(f"--count = {args.count} is out of range; expected >= 1")
    re_min = _finite("--re-min", args.re_min)
    if re_min >= 0:
        raise UsageError(f"--re-min = {re_min:g} must be negative, so that s = 0 lies in the box")
    try:
        steady = steady_state(case.groups, case.w0, case.omega0)
    except NoSteadyDrilling as exc:
        if args.json:
            print(json.dumps({"steady_drilling": False, "reason": str(exc), "roots": []}))
        else:
            print(str(exc))
        return 0
    res = stability(case.groups, case.w0, case.omega0, re_min=re_min)
    roots = [[float(r.real), float(r.imag)] for r in res.roots]
    out = {"steady_drilling": True, "w0": case.w0, "omega0": case.omega0,
           "delta_n0": steady.delta_n0, "v0": steady.v0, "t0": steady.t0,
           "tau_n0": steady.tau_n0, "stable": res.stable, "roots": roots[:args.count],
           "roots_found": len(roots), "roots_counted": res.count_argument_principle - 1,
           "complete": res.complete, "re_min": res.re_min, "radius": res.radius,
           "units": "dimensionless: s in 1/t*, v0 in L*/t*, t0 in C, delta_n0 in L*"}
    if case.si:
        sc = case.preset.rig.scales
        out["si"] = {"depth_of_cut_per_rev_m": steady.delta_n0 * case.groups.n * sc.length_m,
                     "rop_m_s": steady.v0 * sc.velocity_m_s,
                     "torque_on_bit_nm": steady.t0 * sc.stiffness_nm_per_rad,
                     "wob_n": case.w0 * sc.force_n, "t_star_s": sc.time_s}
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"steady drilling: depth of cut per blade {steady.delta_n0:.4g} L*, ROP {steady.v0:.4g} "
          f"L*/t*, torque {steady.t0:.4g} C, delay {steady.tau_n0:.4g} t*")
    if case.si:
        si = out["si"]
        print(f"  in SI: d = {si['depth_of_cut_per_rev_m'] * 1e3:.3f} mm/rev, ROP = "
              f"{si['rop_m_s'] * 3600:.2f} m/h, TOB = {si['torque_on_bit_nm'] / 1e3:.3f} kN m")
    print(f"{'stable' if res.stable else 'UNSTABLE'}: {len(roots)} roots with Re s >= {re_min:g} "
          f"besides s = 0 ({'all' if res.complete else 'NOT all'} of the "
          f"{res.count_argument_principle - 1} the argument principle counts); rightmost:")
    for re, im in roots[:args.count]:
        print(f"  s = {re:+.6f} {im:+.6f}i")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        if args.command == "run":
            return run_session(args)
        if args.command == "bag":
            return bag_cli.run(args)
        return {"simulate": cmd_simulate, "stability": cmd_stability}[args.command](args)
    except (UsageError, ParameterError) as exc:
        print(f"drill_sim: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"drill_sim: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("drill_sim: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
