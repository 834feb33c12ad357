"""``drill_sim stability --string-model distributed``: the roots of the distributed string's
characteristic equation Delta_d(s) in a box, how their count was checked, and the string's
natural frequencies off bottom."""

from __future__ import annotations

import argparse
import math

from ..core import DEFAULT_DT, ParameterError, SteadyState
from ..core.stability_distributed import natural_frequencies, string_stability
from .case import Case
from .checks import json_line
from .errors import UsageError
from .single import string_waves

RE_MAX = 5.0         # right edge of the search box [1/t*]
IM_MAX = 20.0        # half-height of the search box [1/t*]: roots above are not searched
TORSIONAL_MODES, AXIAL_MODES = 3, 2


def run_distributed(args: argparse.Namespace, case: Case, steady: SteadyState,
                    re_min: float) -> int:
    """Print (or --json) the distributed string's stability at ``case``."""
    waves = string_waves(case, "distributed", DEFAULT_DT)   # UsageError in groups mode
    try:
        res = string_stability(case.groups, waves, case.w0, case.omega0, re_min=re_min,
                               re_max=RE_MAX, im_max=IM_MAX)
    except ParameterError as exc:
        raise UsageError(f"--string-model distributed with --re-min {args.re_min}: {exc}") \
            from None
    t_star = case.preset.rig.scales.time_s
    tors, axial = natural_frequencies(waves, case.groups.psi, count=TORSIONAL_MODES)
    hz = 1.0 / (2.0 * math.pi * t_star)
    roots = [[float(r.real), float(r.imag)] for r in res.roots]
    out = {"steady_drilling": True, "string_model": "distributed", "w0": case.w0,
           "omega0": case.omega0, "delta_n0": steady.delta_n0, "v0": steady.v0, "t0": steady.t0,
           "tau_n0": steady.tau_n0, "stable": res.stable, "roots": roots[:args.count],
           "roots_found": len(roots), "roots_counted": res.count_argument_principle - 1,
           "complete": res.complete, "box": list(res.box),
           "completeness": "argument principle on the box's edge; roots with |Im s| > "
                           f"{IM_MAX:g} are not searched",
           "torsional_frequencies_hz": [float(f * hz) for f in tors],
           "axial_frequencies_hz": [float(f * hz) for f in axial[:AXIAL_MODES]],
           "units": "dimensionless: s in 1/t*, v0 in L*/t*, t0 in C, delta_n0 in L*; "
                    "frequencies in Hz", "t_star_s": t_star}
    if args.json:
        print(json_line(out))
        return 0
    x0, x1, _, y1 = res.box
    print(f"distributed string, preset {case.preset.name}: steady drilling at depth of cut per "
          f"blade {steady.delta_n0:.4g} L*, torque {steady.t0:.4g} C, delay "
          f"{steady.tau_n0:.4g} t*")
    print(f"{'stable' if res.stable else 'UNSTABLE'}: {len(roots)} roots of Delta_d(s) in the "
          f"box {x0:g} <= Re s <= {x1:g}, |Im s| <= {y1:g} /t* (up to {y1 * hz:.3g} Hz) besides "
          f"s = 0, {'all' if res.complete else 'NOT all'} of the "
          f"{res.count_argument_principle - 1} the argument principle counts on the box's edge; "
          "roots above the box are not searched; rightmost:")
    for re, im in roots[:args.count]:
        print(f"  s = {re:+.6f} {im:+.6f}i  ({im * hz:+.3f} Hz)")
    print("natural frequencies off bottom (bit free, top speed and hook force held):")
    print("  torsional " + ", ".join(f"{f:.3f}" for f in out["torsional_frequencies_hz"]) +
          " Hz; axial " + ", ".join(f"{f:.3f}" for f in out["axial_frequencies_hz"]) + " Hz")
    return 0
