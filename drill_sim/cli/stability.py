"""``drill_sim stability``: steady drilling and the rightmost roots of Delta(s)."""

from __future__ import annotations

import argparse
import json

from ..core import NoSteadyDrilling, stability, steady_state
from ..core.session import figures_line, key_figures
from .case import add_model_arguments, finite, resolve_case
from .errors import UsageError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_model_arguments(parser)
    parser.add_argument("--re-min", type=float, default=-0.5,
                        help="find every root with Re s >= this [1/t*] (negative)")
    parser.add_argument("--count", type=int, default=8, help="how many roots to print")
    parser.add_argument("--json", action="store_true",
                        help="print the result as one JSON object")


def run(args: argparse.Namespace) -> int:
    case = resolve_case(args)
    if args.count < 1:
        raise UsageError(f"--count = {args.count} is out of range; expected >= 1")
    re_min = finite("--re-min", args.re_min)
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
                     "wob_n": case.w0 * sc.force_n, "t_star_s": sc.time_s,
                     "figures": key_figures(case.preset.rig)}
    if args.json:
        print(json.dumps(out))
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
