"""The options of one simulation that ``simulate`` and ``map`` share: time step, duration,
metrics window, start, gap, perturbation and the top drive, each checked within its documented
range (msg_docs/cli.md, "Limits") and turned, with a ``Case``, into a ``RunSettings``.

Both commands build their runs with ``run_settings`` and run them with
``drill_sim.study.run_single``, so a map point is the simulation ``simulate`` runs, bit for bit.
A new model option (a string model, a top-drive controller) is one more argument here, listed in
``RUN_OPTIONS`` (a map records it among its settings), one more ``RunSettings`` field filled in
``run_settings``, and its use in ``run_single``: both commands then pass it to every run.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass, replace

from ..core import DEFAULT_DT, NoSteadyDrilling, steady_state
from ..core.distributed import STRING_MODELS, geometry_waves
from ..core.parameters import ParameterError
from ..core.resolution import max_step, resolves
from ..core.top_drive import MODES, TopDriveParameters
from ..session.parameter_table import PERTURBATION_RANGE
from ..study.single import RunSettings, default_start
from .case import Case
from .checks import in_range, number, typed
from .errors import UsageError

DT_RANGE = (1e-6, 0.05)        # fixed step [t*]; 0.05 is the core's own upper bound
MAX_STEPS = 1_000_000_000      # per run: about a minute of one core at 20+ million steps/s
STEPS_PER_S = 20e6             # for the time estimate in a refusal
GAP_MAX_M = 10.0               # bit height above bottom, SI [m]
GAP_MAX = 1e4                  # the same, dimensionless [L*]
# the top drive's options: (dest, unit, SI factor, low, high, what), ranges in the unit
DRIVE_OPTIONS = (
    ("top_drive_inertia", "kg m^2", 1.0, 1.0, 1e5, "a top-drive inertia",
     "top_drive_inertia_kg_m2"),
    ("motor_torque_max_knm", "kN m", 1e3, 0.0, 1000.0, "a largest motor torque",
     "motor_torque_max_nm"),
    ("motor_torque_min_knm", "kN m", 1e3, -1000.0, 0.0, "a smallest motor torque (0: the "
     "drive cannot brake)", "motor_torque_min_nm"),
    ("motor_torque_rate_knm_s", "kN m/s", 1e3, 1e-3, 1e6, "a motor torque rate limit",
     "motor_torque_rate_nm_s"),
    ("drive_lag_s", "s", 1.0, 0.0, 10.0, "a motor torque lag", "drive_lag_s"),
    ("drive_kp", "N m s/rad", 1.0, 0.0, 1e8, "a proportional gain", "drive_kp_nm_s_rad"),
    ("drive_ki", "N m/rad", 1.0, 0.0, 1e9, "an integral gain", "drive_ki_nm_rad"),
)
MOTOR_TORQUE_KNM = 1000.0      # |torque mode's command| [kN m]
RUN_OPTIONS = ("start", "gap", "perturbation", "top_drive_mode",   # as typed; the times are
               *(o[0] for o in DRIVE_OPTIONS), "motor_torque_knm",  # in ``Timing``
               "string_model")


@dataclass(frozen=True)
class Drive:
    """The top drive of every run, SI: its parameters and, in torque mode, the motor torque
    command [N m] (None: the start's, the steady torque or 0 at rest)."""

    top_drive: TopDriveParameters
    motor_torque_nm: float | None = None


@dataclass(frozen=True)
class Timing:
    """The run's times in the user's unit (``unit``: s in SI mode, t* in groups mode)."""

    unit: str
    t_star_s: float    # seconds per user time unit: t* in SI mode, 1 in groups mode
    dt: float
    duration: float
    window: float      # the metrics window: the run's last ``window``


def add_run_arguments(parser: argparse.ArgumentParser, *, duration_default: str) -> None:
    """--duration, --dt, --metrics-window, --start, --gap, --perturbation and the top drive's."""
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
    add_drive_arguments(parser)


def add_drive_arguments(parser: argparse.ArgumentParser) -> None:
    """The top drive's options (SI mode): its mode, parameters and torque command."""
    g = parser.add_argument_group("top drive (SI mode; default: the preset's, kinematic)")
    g.add_argument("--top-drive-mode", choices=MODES, default=None,
                   help="kinematic: the ideal speed source of the seed (default); speed: the "
                        "drive's PI holds --rpm; torque: --motor-torque-knm is the motor torque")
    for dest, unit, _, low, high, what, _ in DRIVE_OPTIONS:
        g.add_argument("--" + dest.replace("_", "-"), type=number, default=None,
                       help=f"{what} [{unit}], {low:g} to {high:g}; default: the preset's")
    g.add_argument("--motor-torque-knm", type=number, default=None,
                   help=f"torque mode: the motor torque command [kN m], -{MOTOR_TORQUE_KNM:g} "
                        f"to {MOTOR_TORQUE_KNM:g}; default: the steady torque (steady start) "
                        "or 0")


def resolve_drive(args: argparse.Namespace, case: Case) -> Drive | None:
    """The top drive the options describe (None: kinematic in dimensionless mode); options that
    do nothing in the chosen mode are refused, as are values out of their ranges."""
    given = [d for d in ("top_drive_mode", *(o[0] for o in DRIVE_OPTIONS), "motor_torque_knm")
             if getattr(args, d) is not None]
    if not case.si:
        if given:
            raise UsageError(f"--{given[0].replace('_', '-')}: the top drive's options are SI; "
                             "expected SI mode (--preset) or no top-drive option")
        return None
    base = case.preset.top_drive
    mode = args.top_drive_mode or base.top_drive_mode
    idle = {"kinematic": [d for d in given if d != "top_drive_mode"],
            "speed": [d for d in given if d == "motor_torque_knm"],
            "torque": [d for d in given if d in ("drive_kp", "drive_ki")]}[mode]
    if idle:
        needs = ("torque" if idle[0] == "motor_torque_knm" else
                 "speed" if idle[0] in ("drive_kp", "drive_ki") else "speed or torque")
        raise UsageError(f"--{idle[0].replace('_', '-')} does nothing with the {mode} top drive; "
                         f"expected it with --top-drive-mode {needs}")
    values = {}
    for dest, unit, factor, low, high, what, field in DRIVE_OPTIONS:
        value = getattr(args, dest)
        if value is not None:
            values[field] = factor * in_range("--" + dest.replace("_", "-"), value, low, high,
                                              unit=unit, what=what)
    try:                               # the drive's own rules (limits, gains) decide
        top_drive = replace(base, top_drive_mode=mode, **values)
    except ParameterError as exc:
        raise UsageError(_drive_refusal(str(exc), args, case)) from None
    torque = None if args.motor_torque_knm is None else 1e3 * in_range(
        "--motor-torque-knm", args.motor_torque_knm, -MOTOR_TORQUE_KNM, MOTOR_TORQUE_KNM,
        unit="kN m", what="a motor torque command")
    return Drive(top_drive, torque)


def _drive_refusal(words: str, args: argparse.Namespace, case: Case) -> str:
    """The drive's refusal, naming the option that set what it refuses."""
    if words.startswith("drive_kp_nm_s_rad = None"):
        return (f"--top-drive-mode speed: preset {case.preset.name!r} has no string geometry "
                f"for the default gain 50 Z; expected --drive-kp ({words})")
    for dest, *_, field in DRIVE_OPTIONS:
        if words.startswith(field + " ") and getattr(args, dest) is not None:
            return f"--{dest.replace('_', '-')} {getattr(args, dest):g}: {words}"
    return f"the top drive's options: {words}"


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
    """--gap (in the user's length unit) and --perturbation, checked; a gap is refused without
    --start rest, where it would be silently ignored."""
    gap = in_range("--gap", args.gap, 0.0, GAP_MAX_M if case.si else GAP_MAX,
                   unit="m" if case.si else "L*", what="a bit height above bottom")
    if gap > 0.0 and args.start != "rest":
        start = (f"--start {args.start}" if args.start else
                 "the default start (steady drilling where it exists)")
        raise UsageError(f"--gap {args.gap:g} does nothing with {start}; expected it with "
                         "--start rest (the bit at rest that height above bottom)")
    perturbation = in_range("--perturbation", args.perturbation, *PERTURBATION_RANGE,
                            what="a relative perturbation of the bit speed")
    return gap, perturbation


def run_settings(case: Case, timing: Timing, start: str | None, gap: float,
                 perturbation: float, *, drive: Drive | None = None,
                 where: str = "", string_model: str | None = None) -> RunSettings:
    """The run of ``case``: ``start`` None picks steady drilling when it exists; ``gap`` is in
    m (SI) or L*; ``drive`` the top drive (None: kinematic). A steady start where there is none
    (or that the drive's torque limits cannot hold), or a step that cannot resolve the top
    drive, is a UsageError (``where`` names the point, for a map). ``string_model`` None is the
    preset's (lumped in groups mode); with the distributed string a top drive in the loop is
    the string's top boundary."""
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
    waves = string_waves(case, string_model, timing.dt / t_star)
    groups, torque = None, None
    if drive is not None and drive.top_drive.top_drive_mode != "kinematic":
        rig = case.preset.rig
        groups = drive.top_drive.groups(rig.scales, rig.bha_inertia_kg_m2)
        if not resolves(case.groups, groups, timing.dt / t_star):
            limit = max_step(case.groups, groups)
            raise UsageError(f"--dt {timing.dt:.4g} s cannot resolve the top drive's fastest "
                             f"mode{where}: expected at most {limit * t_star:.4g} s, or a "
                             "heavier --top-drive-inertia")
        if start == "steady":
            t0 = steady_state(case.groups, case.w0, case.omega0).t0
            if waves is not None:           # the torque at the top of the pipe
                t0 = waves.steady_top_torque(t0, case.omega0)
            if not groups.holds(t0):
                c = rig.torsional_stiffness_nm_per_rad
                raise UsageError(f"--start steady{where}: steady drilling needs a motor torque of "
                                 f"{t0 * c / 1e3:.4g} kN m, beyond the drive's limits "
                                 f"{groups.t_min * c / 1e3:g} to {groups.t_max * c / 1e3:g} kN m; "
                                 "expected --start rest or wider limits")
        if drive.motor_torque_nm is not None:
            torque = drive.motor_torque_nm / rig.torsional_stiffness_nm_per_rad
    return RunSettings(
        groups=case.groups, w0=case.w0, omega0=case.omega0, dt=timing.dt / t_star,
        lead=(timing.duration - timing.window) / t_star, window=timing.window / t_star,
        start=start, gap=gap / case.preset.rig.scales.length_m if case.si else gap,
        perturbation=perturbation, drive=groups, motor_torque=torque,
        waves=waves)


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


def formations_note(case: Case, program: str) -> None:
    """Say on stderr that ``program`` (one rock throughout) does not follow the preset's
    formations, which every rig session does (the node, run, control, bag resim)."""
    string = case.preset.string if case.si else None
    if string is not None and string.well is not None and string.well.formations:
        n = len(string.well.formations)
        print(f"{program}: note: the preset's {n} formation{'s' * (n > 1)} along the hole "
              f"{'are' if n > 1 else 'is'} not followed here (one rock throughout: its bit "
              "section's); the node, drill_sim run and drill_sim control follow them",
              file=sys.stderr)


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
