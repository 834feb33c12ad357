"""The off-bottom start-up of ``field_a`` (msg_docs/model.md, "Field presets"): for each speed
set-point, the string from rest 5 cm off bottom, the hook holding all of it, the set-point
ramped from 0 in 10 s and held; prints when the bit breaks free, the peak surface torque, how
often the bit sticks again after that, and its speed range over the last half of the run (at
most the last 30 s).

``--static MU`` replaces the wall's static friction (0.885; the sliding one is 0.425): with
0.425 the two are equal and the start-up settles. The step is 0.1 ms (``--dt``), finer than
the model's default (0.25 ms on field_a, the step the node takes at 1 kHz), as the published
start-ups are compared at; the real-time factor is printed for the step run. The set-point is
moved and the rig sampled every ``--sample-s`` (10 ms), each time from Python (about 9 µs);
``--sample-s 1`` moves the set-point in steps of a second and leaves the kernel nearly alone
in the timing (its table is then that staircase's, not the ramp's).

Run: .venv/bin/python benchmarks/field_a_startup.py [--rpm 10 20 30 60 90] [--seconds 60]
     [--dt 1e-4 | --dt default] [--static 0.425] [--sample-s 0.01]
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace

import numpy as np

from drill_sim.core.presets import load_preset
from drill_sim.core.rig import Rig

RPM = 2.0 * math.pi / 60.0
SAMPLE_S = 0.01


def start_up(rpm: float, seconds: float, ramp_s: float = 10.0,
             dt_s: float | None = 1e-4, static: float | None = None,
             sample_s: float = SAMPLE_S) -> dict[str, np.ndarray]:
    """The run's samples ("t", "bit", "torque") and, as "seconds", the wall-clock time of its
    stepping and sampling (the rig's construction left out)."""
    preset = load_preset("field_a")
    if static is not None:                   # the wall's static friction replaced
        well = replace(preset.string.well, friction_static=static)
        preset = replace(preset, string=replace(preset.string, well=well))
    rig = Rig(preset.rig, dt_s, top_drive=preset.top_drive, string_model="distributed",
              geometry=preset.string)
    rig.start_at_rest(0.05)
    n = round(seconds / sample_s)
    out = {k: np.empty(n) for k in ("t", "bit", "torque")}
    began = time.perf_counter()
    for k in range(n):
        t = (k + 1) * sample_s
        rig.command(min(t / ramp_s, 1.0) * rpm * RPM, preset.rig.submerged_weight_n)
        rig.advance_to(t)
        s = rig.sample()
        out["t"][k], out["bit"][k], out["torque"][k] = t, s.bit_speed_rad_s, s.surface_torque_nm
    out["seconds"] = np.array(time.perf_counter() - began)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--rpm", type=float, nargs="+", default=[10, 20, 30, 60, 90])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--dt", default="1e-4", help="model step [s], or 'default' (the "
                        "model's, 0.25 ms on field_a)")
    parser.add_argument("--sample-s", type=float, default=SAMPLE_S,
                        help="the interval [s] the set-point is moved and the rig sampled at "
                        "(0.01)")
    parser.add_argument("--static", type=float, default=None,
                        help="the wall's static friction coefficient (default the preset's, "
                        "0.885; at least its sliding one, 0.425)")
    args = parser.parse_args()
    try:
        dt_s = None if args.dt == "default" else float(args.dt)
    except ValueError:
        parser.error(f"--dt {args.dt!r}: expected a step in seconds or 'default'")
    if dt_s is not None and not 1e-6 <= dt_s <= 1e-3:
        parser.error(f"--dt {args.dt}: expected 1e-6 to 1e-3 s")
    if not 1.0 <= args.seconds <= 3600.0:
        parser.error(f"--seconds {args.seconds:g}: expected 1 to 3600 s")
    tail_s = min(30.0, 0.5 * args.seconds)
    if any(not 0.0 < r <= 300.0 for r in args.rpm):
        parser.error(f"--rpm {' '.join(f'{r:g}' for r in args.rpm)}: expected set-points "
                     "above 0 and at most 300 rpm")
    if args.static is not None and not 0.425 <= args.static <= 2.0:
        parser.error(f"--static {args.static:g}: expected 0.425 (the sliding friction) to 2")
    if not 1e-3 <= args.sample_s <= 10.0:
        parser.error(f"--sample-s {args.sample_s:g}: expected 0.001 to 10 s")
    start_up(args.rpm[0], 1.0, dt_s=dt_s, sample_s=args.sample_s)   # the compiled code loaded
    print(f"set-point [rpm] | bit free at [s] | peak surface torque [kN m] | sticks again | "
          f"last {tail_s:g} s bit speed [rad/s] | real-time factor")
    for rpm in args.rpm:
        run = start_up(rpm, args.seconds, dt_s=dt_s, static=args.static,
                       sample_s=args.sample_s)
        rtf = args.seconds / float(run["seconds"])
        moving = run["bit"] > 1e-6
        turning = run["bit"] > 1e-3
        free = int(np.argmax(turning))
        again = int(np.sum(np.diff(moving[free:].astype(int)) == -1))
        late = run["t"] > args.seconds - tail_s
        when = f"{run['t'][free]:.1f}" if turning.any() else "never"
        print(f"{rpm:g} | {when} | {run['torque'].max() / 1e3:.1f} | {again} | "
              f"{run['bit'][late].min():.2f} to {run['bit'][late].max():.2f} | {rtf:.0f}")


if __name__ == "__main__":
    main()
