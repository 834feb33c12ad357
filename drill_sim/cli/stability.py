"""``drill_sim stability``: steady drilling and the rightmost roots of Delta(s)."""

from __future__ import annotations

import argparse
import math

from ..core import RPM, Groups, NoSteadyDrilling, ParameterError, steady_state
from ..core.distributed import STRING_MODELS
from ..core.figures import figures_line, key_figures
from ..core.stability import stability
from .case import OMEGA0_MAX, RPM_MAX, Case, add_model_arguments, resolve_case
from .checks import in_range, integer, json_line, number, typed
from .errors import UsageError
from .single import add_drive_arguments
from .stability_string import run_distributed

# The documented limits (msg_docs/cli.md, "Limits").
RE_MIN_RANGE = (-100.0, -1e-6)     # left edge of the search box [1/t*]
MAX_ROOTS = 120                    # roots the search box may hold (estimate), see _root_estimate


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_model_arguments(parser)
    parser.add_argument("--re-min", type=number, default=-0.5,
                        help="find every root with Re s >= this [1/t*], "
                             f"{RE_MIN_RANGE[0]:g} to {RE_MIN_RANGE[1]:g}; default -0.5")
    parser.add_argument("--count", type=integer, default=8, help="how many roots to print")
    parser.add_argument("--json", action="store_true",
                        help="print the result as one JSON object (strict: null, never NaN)")
    parser.add_argument("--string-model", choices=STRING_MODELS, default=None,
                        help="lumped: the roots of Delta(s); distributed (SI mode): those of "
                             "Delta_d(s), the string's natural frequencies and its damped modes "
                             "off bottom with the top drive's boundary; default: the preset's")
    add_drive_arguments(parser)
    parser.add_argument("--law", choices=("stiff_pi", "soft_speed", "z_torque", "off"),
                        default=None,
                        help="with --string-model distributed: the damped modes with this law "
                             "(its reference gains for the preset's distributed string) on the "
                             "top drive's inertia, instead of the drive's own loop: the "
                             "closed-loop roots, each mode's frequency and growth rate")
    parser.add_argument("--sample-period", type=number, default=None,
                        help="with --law: the law's sample period [s], 1e-4 to 0.1; default "
                             "0.001 (the node's tick, as drill_sim control)")


def run(args: argparse.Namespace) -> int:
    case = resolve_case(args)
    if args.count < 1:
        raise UsageError(f"--count {args.count}: out of range; expected a whole number >= 1")
    re_min = in_range("--re-min", args.re_min, *RE_MIN_RANGE, unit="1/t*",
                      what="a negative real part")
    speed = "--rpm" if case.si else "--omega0"
    if case.omega0 == 0:
        raise UsageError(f"{speed} 0: there is no steady drilling without rotation; expected a "
                         "top-drive speed > 0")
    try:
        steady = steady_state(case.groups, case.w0, case.omega0)
    except NoSteadyDrilling as exc:
        if args.json:
            print(json_line({"steady_drilling": False, "reason": str(exc), "roots": []}))
        else:
            print(str(exc))
        return 0
    model = args.string_model or (case.preset.string_model if case.si else "lumped")
    if model != "distributed":
        for option in ("law", "sample_period"):
            if getattr(args, option) is not None:
                raise UsageError(f"--{option.replace('_', '-')}: the closed-loop roots are the "
                                 "distributed string's; expected it with --string-model "
                                 "distributed")
    if model == "distributed":
        return run_distributed(args, case, steady, re_min)
    drive_options = [a for a in vars(args) if a.startswith(("top_drive", "drive_", "motor_"))
                     and getattr(args, a) is not None]
    if drive_options:
        raise UsageError(f"--{drive_options[0].replace('_', '-')}: the top drive is the boundary "
                         "of the distributed string's modes; expected it with --string-model "
                         "distributed")
    _check_root_search(args, case, re_min)
    try:
        res = stability(case.groups, case.w0, case.omega0, re_min=re_min)
    except ParameterError as exc:
        raise UsageError(f"{speed} {_given_speed(args, case)} with --re-min {typed(args.re_min)}: "
                         f"{exc}") from None
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
                     "wob_n": case.w0 * sc.force_n, "t_star_s": sc.time_s,
                     "figures": key_figures(case.preset.rig)}
    if args.json:
        print(json_line(out))
        return 0
    print(f"steady drilling: depth of cut per blade {steady.delta_n0:.4g} L*, ROP {steady.v0:.4g} "
          f"L*/t*, torque {steady.t0:.4g} C, delay {steady.tau_n0:.4g} t*")
    if case.si:
        si = out["si"]
        print(f"  in SI: d = {si['depth_of_cut_per_rev_m'] * 1e3:.3f} mm/rev, ROP = "
              f"{si['rop_m_s'] * 3600:.2f} m/h, TOB = {si['torque_on_bit_nm'] / 1e3:.3f} kN m")
        print(f"  rig: {figures_line(case.preset.rig)}")
    print(f"{'stable' if res.stable else 'UNSTABLE'}: {len(roots)} roots with Re s >= {re_min:g} "
          f"besides s = 0 ({'all' if res.complete else 'NOT all'} of the "
          f"{res.count_argument_principle - 1} the argument principle counts); rightmost:")
    for re, im in roots[:args.count]:
        print(f"  s = {re:+.6f} {im:+.6f}i")
    return 0


def _root_estimate(groups: Groups, w0: float, omega0: float, re_min: float) -> tuple[float, float]:
    """(R, roots): the radius of the disc core.stability searches (the bound of its docstring)
    and about how many roots the box [re_min, R] x [-R, R] holds, R tau_n0 / pi (the roots
    repeat every 2 pi / tau_n0 along the imaginary axis). Both inf when they overflow; the
    search's work and memory grow with the second."""
    tau = 2.0 * math.pi / (groups.n * omega0)
    k = groups.n * (w0 - groups.lam) / (2.0 * math.pi)
    try:
        e_max = 1.0 + math.exp(-re_min * tau)
        a = 1.0 + (groups.n * groups.psi + abs(k)) * e_max
        b = groups.n * groups.psi * e_max
        radius = 1.05 * math.sqrt(0.5 * (a + math.sqrt(a * a + 4.0 * b)))
    except OverflowError:
        return math.inf, math.inf
    return radius, radius * tau / math.pi


def _check_root_search(args: argparse.Namespace, case: Case, re_min: float) -> None:
    """Refuse a speed and --re-min whose search box would hold more than MAX_ROOTS roots,
    naming the least speed and the lowest --re-min that would do."""
    radius, roots = _root_estimate(case.groups, case.w0, case.omega0, re_min)
    if roots <= MAX_ROOTS:
        return

    def fits(omega0: float, r: float) -> bool:
        return _root_estimate(case.groups, case.w0, omega0, r)[1] <= MAX_ROOTS

    per_unit = case.preset.rig.scales.time_s * RPM if case.si else 1.0   # omega0 per rpm
    speed_name, top = ("--rpm", RPM_MAX) if case.si else ("--omega0", OMEGA0_MAX)
    speed = case.omega0 / per_unit
    ways = []
    if fits(top * per_unit, re_min):
        least = _bisect(lambda x: fits(x * per_unit, re_min), speed, top)
        ways.append(f"raise {speed_name} to {_up(least):g} or more")
    if fits(case.omega0, RE_MIN_RANGE[1]):
        highest = _bisect(lambda x: fits(case.omega0, x), re_min, RE_MIN_RANGE[1])
        ways.append(f"bring --re-min up to {_up(highest):g} or more")
    raise UsageError(
        f"{speed_name} {_given_speed(args, case)} with --re-min {typed(args.re_min)}: the root "
        f"search would cover |s| up to {_amount(radius)} /t* and hold {_amount(roots)} roots; "
        f"expected at most {MAX_ROOTS}" + (": " + " or ".join(ways) if ways else ""))


def _given_speed(args: argparse.Namespace, case: Case) -> str:
    """The speed option as typed, or the preset's default."""
    value = args.rpm if case.si else args.omega0
    return typed(value) if value is not None else f"{case.preset.top_drive_speed_rpm:g} (the " \
        "preset's)"


def _bisect(ok, bad: float, good: float) -> float:
    """The value between ``bad`` (not ``ok``) and ``good`` (``ok``) where ``ok`` starts to hold,
    rounded toward ``good``."""
    for _ in range(80):
        middle = 0.5 * (bad + good)
        if ok(middle):
            good = middle
        else:
            bad = middle
    return good


def _up(x: float) -> float:
    """``x`` rounded up to three significant digits."""
    step = 10.0 ** (math.floor(math.log10(abs(x))) - 2)
    return math.ceil(x / step) * step


def _amount(x: float) -> str:
    return f"about {x:.3g}" if math.isfinite(x) else "more than 1e308"
