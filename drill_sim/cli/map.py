"""``drill_sim map``: stick-slip maps over two swept quantities (by default top-drive speed and
weight on bit), every point one ordinary simulation, on every core of this machine or on a
Dask cluster; resumable, written as CSV with a JSON description, optionally plotted."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from .. import __version__
from ..core import ParameterError, Simulator
from ..study.figure import plot_map
from ..study.parallel import (
    ClusterError,
    available_cores,
    check_address,
    compute,
    require_distributed,
)
from ..study.store import MapStore, StoreError, description_path
from ..study.table import METRIC_NAMES, METRICS, metric_row, metric_units
from ..study.theory import theory_lines
from ..terminal import Progress
from .checks import integer, output_file, plot_file, whole
from .errors import UsageError
from .map_grid import BY_DEST, Grid, add_quantity_arguments, build_grid
from .single import (
    RUN_OPTIONS,
    Timing,
    add_run_arguments,
    formations_note,
    resolve_drive,
    resolve_start,
    resolve_timing,
    run_settings,
)

MAX_WORKERS = 1024
FINE = 160               # points per axis on which the theory lines are evaluated


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_quantity_arguments(parser)
    add_run_arguments(parser, duration_default="60 s or 300 t* per point")
    parser.add_argument("--out", type=Path, default=Path("drill_sim_map.csv"),
                        help="CSV of the map, one row per point (default drill_sim_map.csv); "
                             "its description goes beside it as .json; an interrupted map "
                             "resumes from it")
    parser.add_argument("--plot", type=Path, help="figure of the map (.png, .pdf, .svg...)")
    parser.add_argument("--metric", choices=METRIC_NAMES, default="stick_fraction",
                        help="the metric the figure shows; default stick_fraction")
    parser.add_argument("--workers", type=integer, default=None,
                        help=f"processes on this machine, 1 to {MAX_WORKERS}; default: every "
                             f"core ({available_cores()} here)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="send the points to the Dask cluster whose scheduler is at ADDRESS "
                             "(tcp://host:8786)")


def run(args: argparse.Namespace) -> int:
    grid = build_grid(args)
    first = grid.case(0)
    timing = resolve_timing(args, first, 60.0, 300.0)
    gap, perturbation = resolve_start(args, first)
    drive = resolve_drive(args, first)
    if args.scheduler is not None and args.workers is not None:
        raise UsageError(f"--workers {args.workers} with --scheduler {args.scheduler}: the "
                         "cluster's workers run the points; expected one of them")
    workers = available_cores() if args.workers is None else whole(
        "--workers", args.workers, 1, MAX_WORKERS, what="a process count")
    if args.scheduler is not None:
        try:
            check_address(args.scheduler)
            require_distributed()
        except ClusterError as exc:
            raise UsageError(f"--scheduler {args.scheduler}: {exc}") from None
    output_file("--out", args.out)
    output_file("--out", description_path(args.out))
    if args.plot is not None:
        plot_file("--plot", args.plot)
        if grid.x_values.size < 2 or grid.y_values.size < 2:
            raise UsageError(f"--plot {args.plot}: the map has {grid.x_values.size} x "
                             f"{grid.y_values.size} points; expected at least two values of "
                             f"{grid.x.option} and of {grid.y.option}")
    formations_note(grid.case(0), "drill_sim map")
    points = [run_settings(grid.case(p), timing, args.start, gap, perturbation, drive=drive,
                           where=f" at {grid.label(p)}", string_model=args.string_model)
              for p in range(grid.size)]
    _preflight(grid, points)

    columns = ["point", grid.x.column, grid.y.column, *metric_units(grid.si)]
    store = MapStore(args.out, columns, grid.size, _description(args, grid, timing, columns))
    try:
        kept = store.open()
    except StoreError as exc:
        raise UsageError(f"--out {args.out}: {exc}") from None
    if store.discarded:
        shown = "; ".join(f"line {n}: {why}" for n, why in store.discarded[:3])
        more = f" (and {len(store.discarded) - 3} more)" if len(store.discarded) > 3 else ""
        print(f"drill_sim map: resuming {args.out}: {len(kept)} points kept, "
              f"{len(store.discarded)} damaged line(s) left out and their points computed "
              f"again: {shown}{more}", file=sys.stderr)
    pending = [p for p in range(grid.size) if p not in kept]
    started = time.monotonic()
    _compute(args, grid, points, pending, store, workers)
    store.finish()
    elapsed = time.monotonic() - started
    if args.plot is not None:
        _plot(args, grid, store.rows, timing)
    stuck = sum(1 for r in store.rows.values() if r[columns.index("stick_fraction") - 1] > 0)
    where = f"the Dask cluster at {args.scheduler}" if args.scheduler else \
        f"{min(workers, len(pending))} worker(s)"
    done = f"{len(pending)} computed in {elapsed:.1f} s on {where}" if pending else \
        "nothing to compute"
    lines = [f"drill_sim map: {grid.x_values.size} x {grid.y_values.size} points "
             f"({grid.x.option} by {grid.y.option}), {timing.duration:g} {timing.unit} each; "
             f"{done}, {len(kept)} kept from before",
             f"stick-slip at {stuck} of {grid.size} points",
             f"CSV written to {args.out}, description to {store.json_path}"]
    if args.plot is not None:
        lines.append(f"plot written to {args.plot}")
    print("\n".join(lines))
    return 0


def _preflight(grid: Grid, points: list) -> None:
    """Make each distinct model once, so that a parameter the core refuses (such as a step too
    long for the fastest mode) stops the map before anything runs, naming a point."""
    seen = set()
    for p, s in enumerate(points):
        if (s.groups, s.dt) in seen:
            continue
        seen.add((s.groups, s.dt))
        try:
            Simulator(s.groups, s.dt)
        except ParameterError as exc:
            raise UsageError(f"at {grid.label(p)}: {exc}") from None


def _compute(args: argparse.Namespace, grid: Grid, points: list, pending: list[int],
             store: MapStore, workers: int) -> None:
    """Run the pending points, storing each as it finishes, with a progress bar."""
    progress = Progress("map")
    done_before = grid.size - len(pending)
    try:
        results = compute([points[p] for p in pending], workers=workers,
                          scheduler=args.scheduler)
        for n, (k, metrics) in enumerate(results, 1):
            p = pending[k]
            v = grid.values(p)
            row = metric_row(metrics, points[p].omega0, grid.preset.rig if grid.si else None)
            store.append(p, [v[grid.x.dest], v[grid.y.dest], *row.values()])
            progress.label = f"map {done_before + n:>{len(str(grid.size))}}/{grid.size} points"
            progress(n / len(pending))
    except ClusterError as exc:
        progress.close()
        store.close()
        raise UsageError(f"--scheduler {args.scheduler}: {exc}") from None
    except BaseException:
        progress.close()
        try:
            store.finish()       # the points done, in grid order; the description says how many
        except OSError:
            store.close()
        print(f"drill_sim map: {len(store.rows)} of {grid.size} points kept in {args.out}; "
              "run the same command again to resume", file=sys.stderr)
        raise
    progress.close()


def _description(args: argparse.Namespace, grid: Grid, timing: Timing,
                 columns: list[str]) -> dict:
    """The JSON description: ``settings`` (what must match to resume) and what the CSV holds."""
    model = {"preset": grid.preset.name, "rig": grid.preset.rig.as_dict()} if grid.si else \
        {"groups": {"n": grid.groups.n, "psi": grid.groups.psi, "lambda": grid.groups.lam,
                    "beta": grid.groups.beta}}
    settings = {
        "package_version": __version__, "mode": "si" if grid.si else "dimensionless", **model,
        "x": {"quantity": grid.x.column, "values": grid.x_values.tolist()},
        "y": {"quantity": grid.y.column, "values": grid.y_values.tolist()},
        "fixed": {BY_DEST[d].column: v for d, v in grid.fixed.items()},
        "time_unit": timing.unit, "dt": timing.dt, "duration": timing.duration,
        "metrics_window": timing.window,
        **{name: getattr(args, name) for name in RUN_OPTIONS}}
    settings["start"] = settings["start"] or "steady where it exists, else rest"
    units = {"point": "index: x index * len(y values) + y index", grid.x.column: grid.x.unit,
             grid.y.column: grid.y.unit, **metric_units(grid.si)}
    return {"settings": settings, "columns": {c: units[c] for c in columns},
            "definitions": DEFINITIONS}


DEFINITIONS = {
    "metrics_window": "metrics over the last metrics_window of each point's duration",
    "ssi": "(max - min bit speed) / (2 mean bit speed)",
    "stick_fraction": "share of the window with the bit stuck (zero speed in contact)",
    "bounce_fraction": "share of the window with the bit off bottom",
    "speed_drop": "(top-drive speed - min bit speed) / top-drive speed",
    "mse": "mechanical specific energy W/A + 2 pi N T/(A ROP), A = pi a^2, N the top-drive "
           "speed [rev/s], T the mean surface torque; groups mode: the rotary term only, "
           "in units of epsilon",
}


def _plot(args: argparse.Namespace, grid: Grid, rows: dict[int, list[float]],
          timing: Timing) -> None:
    column = next(c for c in METRICS if c.name == args.metric)
    index = list(metric_units(grid.si)).index(column.column(grid.si)) + 2
    stick_index = list(metric_units(grid.si)).index("stick_fraction") + 2
    shape = (grid.x_values.size, grid.y_values.size)
    values, stick = np.full(shape, np.nan), np.zeros(shape, dtype=bool)
    for p, row in rows.items():
        i, j = divmod(p, shape[1])
        values[i, j] = row[index] * (column.scale if grid.si else 1.0)
        stick[i, j] = row[stick_index] > 0
    unit = column.display_unit if grid.si else column.groups_unit
    fine = [np.geomspace(v[0], v[-1], FINE) if args.log else np.linspace(v[0], v[-1], FINE)
            for v in (grid.x_values, grid.y_values)]
    d = grid.dimensionless(*fine)
    model = f"preset {grid.preset.name}" if grid.si else f"n = {grid.groups.n}"
    held = ", ".join(f"{BY_DEST[d].symbol} = {v:.4g}{' ' + BY_DEST[d].unit if grid.si else ''}"
                     for d, v in grid.fixed.items())
    plot_map(args.plot, grid.x_values, grid.y_values, values, stick,
             x_label=grid.x.label, y_label=grid.y.label,
             metric_label=f"{column.column(grid.si)} [{unit}]" if not grid.si
             else f"{column.name} [{unit}]",
             fine_x=fine[0], fine_y=fine[1],
             lines=theory_lines(d["n"], d["psi"], d["lam"], d["beta"], d["w0"], d["omega0"]),
             log=args.log, fraction=column.name.endswith("fraction"),
             title=f"drill_sim map, {model}{'; ' + held if held else ''}\n"
                   f"{timing.duration:g} {timing.unit} a point, metrics over the last "
                   f"{timing.window:g} {timing.unit}")

