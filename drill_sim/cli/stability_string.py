"""``drill_sim stability --string-model distributed``: the roots of the distributed string's
characteristic equation Delta_d(s) in a box, how their count was checked, the string's
natural frequencies off bottom, and its damped modes off bottom with the top drive's boundary
(the continuously damped pipe's exact roots)."""

from __future__ import annotations

import argparse
import math

from ..control import make_law
from ..control.evaluation import DEFAULT_SAMPLE_PERIOD_S
from ..control.impedance import top_boundary
from ..control.reference import reference_gains
from ..control.tuning import pipe_impedance
from ..core import DEFAULT_DT, ParameterError, SteadyState
from ..core.distributed import geometry_waves
from ..core.stability_distributed import natural_frequencies, string_modes, string_stability
from .case import Case
from .checks import json_line, sample_period
from .errors import UsageError
from .single import resolve_drive, string_waves

RE_MAX = 5.0         # right edge of the search box [1/t*]
IM_MAX = 20.0        # half-height of the search box [1/t*]: roots above are not searched
TORSIONAL_MODES, AXIAL_MODES = 3, 2
DAMPED_MODES = 5     # damped modes reported of each family


def run_distributed(args: argparse.Namespace, case: Case, steady: SteadyState,
                    re_min: float) -> int:
    """Print (or --json) the distributed string's stability at ``case``."""
    string_waves(case, "distributed", DEFAULT_DT)   # UsageError in groups mode, no geometry
    if args.law is not None:
        # the law commands the motor torque: the drive in torque mode, its own loop unused
        for option in ("top_drive_mode", "drive_kp", "drive_ki", "motor_torque_knm"):
            if getattr(args, option) is not None:
                raise UsageError(f"--{option.replace('_', '-')} with --law: the law commands "
                                 "the motor torque of the drive (torque mode); expected the "
                                 "drive's inertia, limits and lag only")
        args.top_drive_mode = "torque"
    drive = resolve_drive(args, case)
    assert drive is not None                            # SI mode
    rig = case.preset.rig
    # the exact damped pipe: the roots and the modes are the string's, not its simulation's
    waves = geometry_waves(rig, case.preset.string, DEFAULT_DT, continuous=True)
    try:
        res = string_stability(case.groups, waves, case.w0, case.omega0, re_min=re_min,
                               re_max=RE_MAX, im_max=IM_MAX)
    except ParameterError as exc:
        raise UsageError(f"--string-model distributed with --re-min {args.re_min}: {exc}") \
            from None
    t_star = case.preset.rig.scales.time_s
    well = case.preset.string.well
    rubs = well is not None and well.rubs        # set-valued: no linear root sees it
    tors, axial = natural_frequencies(waves, case.groups.psi, count=TORSIONAL_MODES)
    hz = 1.0 / (2.0 * math.pi * t_star)
    roots = [[float(r.real), float(r.imag)] for r in res.roots]
    top, boundary, law_gains = _law_boundary(args, case, drive)
    closed = None
    if top is not None:                  # on bottom with the law at the top: the closed loop
        try:
            closed = string_stability(case.groups, waves, case.w0, case.omega0, re_min=re_min,
                                      re_max=RE_MAX, im_max=IM_MAX, top=top)
        except ParameterError as exc:
            raise UsageError(f"--law {args.law}, the closed loop on bottom: {exc}") from None
    try:
        damped = string_modes(waves, case.groups.psi,
                              drive.top_drive.groups(rig.scales, rig.bha_inertia_kg_m2),
                              count=DAMPED_MODES, top=top)
    except ParameterError as exc:
        raise UsageError(f"--string-model distributed, the damped modes: {exc}") from None
    modes = [{"kind": m.kind, "frequency_hz": m.frequency * hz,
              "damping_ratio": m.damping_ratio, "growth_rate_per_s": m.root.real / t_star}
             for m in (*damped.torsional, *damped.axial)]
    out = {"steady_drilling": True, "string_model": "distributed", "w0": case.w0,
           "omega0": case.omega0, "delta_n0": steady.delta_n0, "v0": steady.v0, "t0": steady.t0,
           "tau_n0": steady.tau_n0, "stable": res.stable, "roots": roots[:args.count],
           "roots_found": len(roots),
           "roots_counted": res.counted,
           "complete": res.complete, "box": list(res.box),
           "completeness": "argument principle on the box's edge; roots with |Im s| > "
                           f"{IM_MAX:g} are not searched",
           "torsional_frequencies_hz": [float(f * hz) for f in tors],
           "axial_frequencies_hz": [float(f * hz) for f in axial[:AXIAL_MODES]],
           "modes": modes, "modes_complete": damped.complete,
           "wall_friction_left_out": rubs,
           "modes_boundary": boundary, **law_gains,
           **({} if closed is None else {"closed_loop_on_bottom": {
               "stable": closed.stable,
               "roots": [[float(r.real), float(r.imag)] for r in closed.roots][:args.count],
               "roots_found": int(closed.roots.size),
               # the argument principle counts the roots less the law's poles in the box
               "roots_counted": closed.counted,
               "complete": bool(closed.roots.size >= closed.counted)}}),
           "units": "dimensionless: s in 1/t*, v0 in L*/t*, t0 in C, delta_n0 in L*; "
                    "frequencies in Hz (modes: the damped frequency Im s / 2 pi, damping ratio "
                    "-Re s / |s|)", "t_star_s": t_star}
    if args.json:
        print(json_line(out))
        return 0
    x0, x1, _, y1 = res.box
    print(f"distributed string, preset {case.preset.name}: steady drilling at depth of cut per "
          f"blade {steady.delta_n0:.4g} L*, torque {steady.t0:.4g} C, delay "
          f"{steady.tau_n0:.4g} t*")
    if rubs:
        print("the well's friction along the string is left out of these roots and modes (it is "
              "set-valued, not linear: msg_docs/model.md, \"A deviated well\"); a simulation "
              "has it")
    print("bit on bottom, the top held (the bit's own regenerative stability, whatever law runs "
          "at the top):")
    print(f"{'stable' if res.stable else 'UNSTABLE'}: {len(roots)} roots of Delta_d(s) in the "
          f"box {x0:g} <= Re s <= {x1:g}, |Im s| <= {y1:g} /t* (up to {y1 * hz:.3g} Hz) besides "
          f"s = 0, {'all' if res.complete else 'NOT all'} of the "
          f"{res.counted} the argument principle counts on the box's edge; "
          "roots above the box are not searched; rightmost:")
    for re, im in roots[:args.count]:
        print(f"  s = {re:+.6f} {im:+.6f}i  ({im * hz:+.3f} Hz)")
    if closed is not None:
        print(f"bit on bottom, {args.law} at the top (the closed loop; the law's own filters' "
              f"roots may be among them): {'stable' if closed.stable else 'UNSTABLE'}, "
              f"{closed.roots.size} roots found in the same box (the argument principle counts "
              f"{closed.counted}: the roots less the "
              "law's poles there); rightmost:")
        for r in closed.roots[:args.count]:
            print(f"  s = {r.real:+.6f} {r.imag:+.6f}i  ({r.imag * hz:+.3f} Hz)")
    print("natural frequencies off bottom (bit free, top speed and hook force held):")
    print("  torsional " + ", ".join(f"{f:.3f}" for f in out["torsional_frequencies_hz"]) +
          " Hz; axial " + ", ".join(f"{f:.3f}" for f in out["axial_frequencies_hz"]) + " Hz")
    print(f"damped modes off bottom ({out['modes_boundary']}; frequency Hz / damping ratio %), "
          f"{'all' if damped.complete else 'NOT all'} found:")
    for kind in ("torsional", "axial"):
        print(f"  {kind:9} " + ", ".join(f"{m['frequency_hz']:.3f} / {100 * m['damping_ratio']:.2f}"
                                        for m in modes if m["kind"] == kind))
    if args.law is not None:
        print(f"  these are the closed loop's with {args.law} at the top (a root of the law's own "
              "filters may be among them): the law's stability, mode by mode; on bottom, the "
              "roots with the top held are the bit's own, and the closed loop's say what the "
              "law changes of them")
    return 0


def _law_boundary(args: argparse.Namespace, case: Case, drive) -> tuple[object, str, dict]:
    """The top boundary of the modes: the drive's own (None) or ``--law``'s, linearised
    (``control.impedance``) in the string's units; its words; the law's gains for the JSON."""
    td = drive.top_drive
    if args.law is None:
        if args.sample_period is not None:
            raise UsageError("--sample-period: the law's sample period; expected it with --law")
        return None, f"bit off bottom, hook force held, top drive {td.top_drive_mode}", {}
    h = DEFAULT_SAMPLE_PERIOD_S if args.sample_period is None else sample_period(
        args.sample_period)
    preset = case.preset
    gains = reference_gains(args.law, preset, td.top_drive_inertia_kg_m2,
                            string_model="distributed", sample_period_s=h)
    try:
        law = make_law(args.law, h, pipe_impedance(preset), td.top_drive_inertia_kg_m2, **gains)
    except ParameterError as exc:
        raise UsageError(f"--law {args.law} with --sample-period {h:g}: its reference gains for "
                         f"this string do not fit that sample period: {exc}") from None
    boundary_si = top_boundary(law, td.drive_lag_s)
    t_star = preset.rig.scales.time_s
    c_unit = preset.rig.scales.stiffness_nm_per_rad

    def top(s):
        k, lag = boundary_si(s / t_star)
        return k / c_unit, lag
    inertia = f"the top drive's inertia {td.top_drive_inertia_kg_m2:g} kg m^2"
    words = (f"bit off bottom, hook force held, law off: the motor torque held on {inertia}"
             if args.law == "off" else
             f"bit off bottom, hook force held, law {args.law} (reference gains for the "
             f"distributed string, h = {h:g} s) on {inertia}")
    return top, words, {"law": args.law, "law_gains": gains, "sample_period_s": h}
