"""The options of one simulation that ``simulate`` and ``map`` share: time step, duration,
metrics window, start, gap and perturbation, each checked within its documented range
(msg_docs/cli.md, "Limits") and turned, with a ``Case``, into a ``RunSettings``.

Both commands build their runs with ``run_settings`` and run them with
``drill_sim.study.run_single``, so a map point is the simulation ``simulate`` runs, bit for bit.
A new model option (a string model, a top-drive controller) is one more argument here, listed in
``RUN_OPTIONS`` (a map records it among its settings), one more ``RunSettings`` field filled in
``run_settings``, and its use in ``run_single``: both commands then pass it to every run.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass

from ..core import DEFAULT_DT, NoSteadyDrilling, steady_state
from ..core.distributed import STRING_MODELS, geometry_waves
from ..study.single import RunSettings, default_start
from .case import Case
from .checks import in_range, number, typed
from .errors import UsageError

DT_RANGE = (1e-6, 0.05)        # fixed step [t*]; 0.05 is the core's own upper bound
MAX_STEPS = 1_000_000_000      # per run: about a minute of one core at 20+ million steps/s
STEPS_PER_S = 20e6             # for the time estimate in a refusal
GAP_MAX_M = 10.0               # bit height above bottom, SI [m]
GAP_MAX = 1e4                  # the same, dimensionless [L*]
PERTURBATION_RANGE = (-0.9, 1.0)
RUN_OPTIONS = ("start", "gap", "perturbation",   # as typed; the times are in ``Timing``
               "string_model")


@dataclass(frozen=True)
class Timing:
    """The run's times in the user's unit (``unit``: s in SI mode, t* in groups mode)."""

    unit: str
    t_star_s: float    # seconds per user time unit: t* in SI mode, 1 in groups mode
    dt: float
    duration: float
    window: float      # the metrics window: the run's last ``window``


def add_run_arguments(parser: argparse.ArgumentParser, *, duration_default: str) -> None:
    """--duration, --dt, --metrics-window, --start, --gap and --perturbation."""
    parser.add_argument("--duration", type=number, default=None,
                        help=f"simulated time [s] (SI) or [t*] (groups); default "
                             f"{duration_default}; at most {MAX_STEPS:,} steps")
    parser.add_argument("--dt", type=number, default=None,
                        help=f"fixed step [s] or [t*], {DT_RANGE[0]:g} to {DT_RANGE[1]:g} t*; "
                             f"default {DEFAULT_DT:g} t*")
    parser.add_argument("--metrics-window", type=number, default=None,
                        help="metrics over the last this much time [s] or [t*]; default: last "
                             "half")
    parser.add_argument("--start", choices=("steady", "rest"), default=None,
                        help="exact steady drilling (default when it exists) or bit at rest")
    parser.add_argument("--gap", type=number, default=0.0,
                        help=f"with --start rest: height of the bit above bottom, 0 to "
                             f"{GAP_MAX_M:g} m or 0 to {GAP_MAX:g} L*")
    parser.add_argument("--perturbation", type=number, default=1e-3,
                        help="relative perturbation of the initial bit speed (steady start), "
                             f"{PERTURBATION_RANGE[0]:g} to {PERTURBATION_RANGE[1]:g}")
    parser.add_argument("--string-model", choices=STRING_MODELS, default=None,
                        help="the drill string: lumped spring or distributed pipe (SI mode "
                             "only, from the preset's geometry); default: the preset's, lumped")


def resolve_timing(args: argparse.Namespace, case: Case, default_s: float,
                   default_t: float) -> Timing:
    """--dt, --duration (default ``default_s`` s or ``default_t`` t*) and --metrics-window."""
    t_star = case.preset.rig.scales.time_s if case.si else 1.0   # user time unit -> t*
    unit = "s" if case.si else "t*"
    dt = DEFAULT_DT * t_star if args.dt is None else in_range(
        "--dt", args.dt, DT_RANGE[0] * t_star, DT_RANGE[1] * t_star, unit=unit,
        what="a time step", note=f"({DT_RANGE[0]:g} to {DT_RANGE[1]:g} t*, t* = {t_star:.4g} s)"
        if case.si else "")
    duration = _duration(args, dt, unit, default_s if case.si else default_t)
    window = 0.5 * duration if args.metrics_window is None else in_range(
        "--metrics-window", args.metrics_window, dt, duration, unit=unit,
        what="a window of at least one step, within --duration")
    return Timing(unit, t_star, dt, duration, window)


def resolve_start(args: argparse.Namespace, case: Case) -> tuple[float, float]:
    """--gap (in the user's length unit) and --perturbation, checked."""
    gap = in_range("--gap", args.gap, 0.0, GAP_MAX_M if case.si else GAP_MAX,
                   unit="m" if case.si else "L*", what="a bit height above bottom")
    perturbation = in_range("--perturbation", args.perturbation, *PERTURBATION_RANGE,
                            what="a relative perturbation of the bit speed")
    return gap, perturbation


def run_settings(case: Case, timing: Timing, start: str | None, gap: float,
                 perturbation: float, *, where: str = "",
                 string_model: str | None = None) -> RunSettings:
    """The run of ``case``: ``start`` None picks steady drilling when it exists; ``gap`` is in
    m (SI) or L*. A steady start where there is none is a UsageError (``where`` names the
    point, for a map). ``string_model`` None is the preset's (lumped in groups mode)."""
    speed = "--rpm" if case.si else "--omega0"
    start = start or default_start(case.groups, case.w0, case.omega0)
    if start == "steady" and case.omega0 == 0:
        raise UsageError(f"--start steady with {speed} 0{where}: there is no steady drilling "
                         "without rotation; expected a top-drive speed > 0 or --start rest")
    if start == "steady":
        try:
            steady_state(case.groups, case.w0, case.omega0)
        except NoSteadyDrilling as exc:
            raise UsageError(f"--start steady{where}: {exc}") from None
    t_star = timing.t_star_s
    return RunSettings(
        groups=case.groups, w0=case.w0, omega0=case.omega0, dt=timing.dt / t_star,
        lead=(timing.duration - timing.window) / t_star, window=timing.window / t_star,
        start=start, gap=gap / case.preset.rig.scales.length_m if case.si else gap,
        perturbation=perturbation, waves=string_waves(case, string_model, timing.dt / t_star))


def string_waves(case: Case, string_model: str | None, dt: float):
    """The distributed string of ``case`` at step ``dt`` [t*], or None for the lumped one;
    a UsageError where there is no pipe geometry (groups mode, a ``lumped:`` preset)."""
    model = string_model or (case.preset.string_model if case.si else "lumped")
    if model == "lumped":
        return None
    if not case.si:
        raise UsageError("--string-model distributed with --groups: the distributed string "
                         "needs the pipe's geometry, which the groups do not give; expected "
                         "--preset (SI mode) or --string-model lumped")
    if case.preset.string is None:
        raise UsageError(f"--string-model distributed with preset {case.preset.name!r}: it gives "
                         "'lumped' C, I, M, W_s, not the pipe's geometry; expected a preset "
                         "with a 'string' section or --string-model lumped")
    return geometry_waves(case.preset.rig, case.preset.string, dt)


def _duration(args: argparse.Namespace, dt: float, unit: str, default: float) -> float:
    """--duration checked: at least one step of ``dt`` and at most MAX_STEPS steps."""
    if args.duration is None:
        duration = default
    else:
        duration = args.duration
        if not (math.isfinite(duration) and duration >= dt):
            raise UsageError(f"--duration {typed(duration)}: "
                             f"{'too short' if math.isfinite(duration) else 'not a finite number'}"
                             f"; expected a simulated time of at least one step, dt = {dt:.4g} "
                             f"{unit}")
    steps = duration / dt
    if steps > MAX_STEPS:
        given = f"--dt {typed(args.dt)}" if args.dt is not None else f"the default dt {dt:.4g}"
        cost = f", about {wall_time(steps / STEPS_PER_S)} of computing" \
            if math.isfinite(steps) else ""
        raise UsageError(
            f"--duration {typed(duration)} {unit} at {given} {unit} is {amount(steps)} steps"
            f"{cost}; expected at most {MAX_STEPS:,} steps: shorten --duration or raise --dt")
    return duration


def amount(x: float) -> str:
    """A count, in full up to 1e12."""
    if not math.isfinite(x):
        return "more than 1e308"
    return f"{x:,.0f}" if x < 1e12 else f"{x:.3g}"


def wall_time(seconds: float) -> str:
    """A duration in the largest unit that fits: ``3.2 hours``."""
    for size, name in ((365.25 * 86400, "years"), (86400, "days"), (3600, "hours"),
                       (60, "minutes")):
        if seconds >= size:
            return f"{seconds / size:.3g} {name}"
    return f"{seconds:.3g} s"
