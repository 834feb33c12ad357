"""``drill_sim tune``: tune a law's gains offline on a scenario set, then write a controller
params file ready for ``drill_sim_controller --params-file`` (``study.gain_tuning``; Optuna:
``pip install -e '.[tune]'``)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..control import LAWS
from ..control.tuning import pipe_impedance
from ..core import load_preset
from ..study import gain_tuning as gt
from ..study.parallel import ClusterError, available_cores
from .checks import number, output_file, plot_file, sample_period, sensor_seed, whole
from .control import add_loop_arguments
from .errors import UsageError

TUNABLE = [name for name, cls in LAWS.items() if cls.GAINS]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--law", required=True, choices=TUNABLE, help="the law to tune")
    parser.add_argument("--params", required=True,
                        help="comma-separated gains to tune, the names --gain of drill_sim "
                             "control takes (e.g. kp_nm_s_rad,alpha)")
    parser.add_argument("--range", action="append", default=[], metavar="NAME=LOW:HIGH",
                        help="a gain's search range (default: its reference value / 4 to x 4, "
                             "log scale); repeatable")
    parser.add_argument("--preset", default="base", help="shipped preset or preset YAML; base")
    parser.add_argument("--scenarios", default="standard",
                        help="the scenario set the trials are scored on (drill_sim control "
                             "--scenarios); default standard")
    parser.add_argument("--trials", type=int, default=40,
                        help="finished trials to reach, 1 to 10000 (a resumed study counts its "
                             "own); default 40")
    parser.add_argument("--workers", type=int, default=None,
                        help=f"processes on this machine (default: every core, "
                             f"{available_cores()} here)")
    parser.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                        help="run the trials on this Dask cluster instead (as drill_sim map)")
    parser.add_argument("--seed", type=int, default=0, help="the sampler's seed, >= 0; default 0")
    add_loop_arguments(parser)
    parser.add_argument("--plot", default=None,
                        help="a figure of the study (.png): each trial's objective and the best "
                             "so far, and the trials in the first two gains' plane")
    parser.add_argument("--out", required=True,
                        help="the controller params file to write (.yaml); the study is kept "
                             "beside it (<out>.journal) and resumed from there")


def run(args: argparse.Namespace) -> int:
    if not args.out.endswith((".yaml", ".yml")):
        raise UsageError(f"--out {args.out}: expected a .yaml file (a ROS params file)")
    out = output_file("--out", Path(args.out))
    if args.plot is not None:
        plot_file("--plot", Path(args.plot))
    try:
        import optuna  # noqa: F401
    except ImportError:
        raise UsageError("drill_sim tune needs Optuna, which is not installed: pip install "
                         "optuna (or the tune extra: pip install -e '.[tune]')") from None
    names = [n.strip() for n in args.params.split(",") if n.strip()]
    ranges = {}
    for item in args.range:
        name, eq, span = item.partition("=")
        low, colon, high = span.partition(":")
        if not eq or not colon:
            raise UsageError(f"--range {item!r}: expected NAME=LOW:HIGH")
        if name not in names:
            raise UsageError(f"--range {item!r}: {name} is not in --params")
        try:
            ranges[name] = (number(low), number(high))
        except argparse.ArgumentTypeError as exc:
            raise UsageError(f"--range {item!r}: {exc}") from None
    trials = whole("--trials", args.trials, 1, 10000)
    workers = (available_cores() if args.workers is None
               else whole("--workers", args.workers, 1, 1024))
    job = gt.TrialJob(preset=args.preset, law=args.law, gains={},
                      scenarios=tuple(args.scenarios.split(",")),
                      sample_period_s=sample_period(args.sample_period),
                      string_model=args.string_model, sensor_profile=args.sensor_profile,
                      sensor_seed=sensor_seed(args.sensor_seed))
    gt.named(list(job.scenarios))                    # a bad set name: refused before any run
    reference = gt.reference_for(job)
    job = gt.TrialJob(**{**job.__dict__, "gains": reference})
    space = gt.search_space(args.law, names, reference, ranges)
    gt.check_ends(job, space)                        # a range the law refuses: before any run
    journal = out.with_suffix(out.suffix + ".journal")
    start = time.monotonic()

    def progress(done: int, total: int) -> None:
        print(f"\rdrill_sim tune: {done}/{total} trials, {time.monotonic() - start:.0f} s",
              end="", file=sys.stderr, flush=True)
    try:
        result = gt.tune(job, space, trials=trials, journal=journal,
                         seed=whole("--seed", args.seed, 0, 2**31 - 1), workers=workers,
                         scheduler=args.scheduler, progress=progress)
    except ClusterError as exc:
        raise UsageError(str(exc)) from None
    print(file=sys.stderr)
    _print(result, space, args, time.monotonic() - start)
    _write(out, args, result)
    print(f"params file written to {out}: drill_sim_controller --ros-args --params-file {out}")
    if args.plot is not None:
        _plot(Path(args.plot), result, list(space))
        print(f"plot written to {args.plot}")
    return 0


def _print(result: gt.TuneResult, space, args, seconds: float) -> None:
    print(f"drill_sim tune: {args.law} on preset {args.preset}, scenarios {args.scenarios}, "
          f"{len(result.trials)} trials in {seconds:.0f} s; objective J = mean over the "
          "scenarios of SSI + 10 stick + 10 max(0, saturation - 0.05), lower is better")
    names = list(space)
    print("| gains | " + " | ".join(names) + " | J | SSI | stick | saturation |")
    print("| --- |" + " --- |" * (len(names) + 4))
    rows = [("reference", result.reference_gains, result.reference)] if result.reference else []
    ranked = sorted(result.trials, key=lambda row: row[1].objective)[:5]
    rows += [(f"best {i + 1}", g, s) for i, (g, s) in enumerate(ranked)]
    for label, gains, s in rows:
        print(f"| {label} | " + " | ".join(f"{gains[n]:.4g}" for n in names)
              + f" | {s.objective:.3f} | {s.ssi:.3f} | {s.stick_fraction:.3f} | "
              f"{s.saturation_fraction:.3f} |")
    if not result.improved:
        print("no trial beat the reference gains by more than 1 % of J: the params file holds "
              "the reference tuning")


def _write(out: Path, args, result: gt.TuneResult) -> None:
    preset = load_preset(args.preset)
    drive = preset.top_drive
    gains = result.best_gains if result.improved else result.reference_gains
    lines = [
        f"# drill_sim_controller, law {args.law}: tuned by drill_sim tune on preset "
        f"{args.preset}, scenarios {args.scenarios}, sensors {args.sensor_profile}, "
        f"{args.string_model} string, h = {args.sample_period:g} s",
        f"# objective J {result.best.objective:.4f} (reference "
        + (f"{result.reference.objective:.4f}" if result.reference else "not run") + ")",
        f"#   drill_sim_controller --ros-args --params-file {out.name}",
        "/**:",
        "  ros__parameters:",
        f"    law: {args.law}",
        "    rig: drill_sim",
        f"    sample_period_s: {args.sample_period!r}",
        f"    impedance_nm_s_rad: {pipe_impedance(preset)!r}",
        f"    top_drive_inertia_kg_m2: {float(drive.top_drive_inertia_kg_m2)!r}",
        "    inputs: measured                # ~/measured/top_drive/... (ideal: the exact values)",
        "    manage_drive_mode: true",
        "    enabled: true",
    ]
    lines += [f"    {args.law}.{k}: {float(v)!r}" for k, v in gains.items()]
    if LAWS[args.law].limited_by_drive:
        for k, v in (("torque_min_nm", drive.motor_torque_min_nm),
                     ("torque_max_nm", drive.motor_torque_max_nm)):
            if k not in gains:
                lines.append(f"    {args.law}.{k}: {float(v)!r}")
    out.write_text("\n".join(lines) + "\n")


def _plot(path: Path, result: gt.TuneResult, names: list[str]) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    j = [s.objective for _, s in result.trials]
    best = [min(j[:k + 1]) for k in range(len(j))]
    fig, axes = plt.subplots(1, 2 if len(names) >= 2 else 1, figsize=(10, 4), squeeze=False)
    ax = axes[0][0]
    ax.plot(range(len(j)), j, "o", ms=4, label="trial")
    ax.plot(range(len(j)), best, "-", label="best so far")
    if result.reference is not None:
        ax.axhline(result.reference.objective, color="0.5", ls="--", label="reference gains")
    ax.set_xlabel("trial")
    ax.set_ylabel("objective J (lower is better)")
    ax.legend()
    if len(names) >= 2:
        ax = axes[0][1]
        x = [g[names[0]] for g, _ in result.trials]
        y = [g[names[1]] for g, _ in result.trials]
        sc = ax.scatter(x, y, c=j, cmap="viridis_r")
        ax.plot([result.reference_gains[names[0]]], [result.reference_gains[names[1]]], "k+",
                ms=14, label="reference")
        ax.plot([result.best_gains[names[0]]], [result.best_gains[names[1]]], "rx", ms=12,
                label="best")
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1])
        ax.legend()
        fig.colorbar(sc, ax=ax, label="J")
    fig.suptitle(f"drill_sim tune: {result.law}, {len(j)} trials")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
