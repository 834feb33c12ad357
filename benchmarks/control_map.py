"""Where top-end control cures stick-slip on the distributed string: the kinematic drive against
Z-Torque's reference tuning (passive up to the fifth mode), over speed and weight, with ideal
and ``surface_rig`` sensors (msg_docs/control.md, "The control map").

    python benchmarks/control_map.py [--preset long] [--rpm 40,55,70,100] \\
        [--wob-kn 80,100,120,160] [--duration 60] [--workers 2] [--plot map.png]

Each point is ``drill_sim control --rpm R --wob-kn W --string-model distributed`` for the
kinematic drive and Z-Torque (the offline loop, 1 ms sample, metrics over the second half).
A point "sticks" where the kinematic drive is stuck >= 20 % of the time; it is "cured" where
Z-Torque there sticks <= 1 %, saturates < 5 % and its SSI is at most 0.75 of the kinematic's.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from concurrent.futures import ProcessPoolExecutor

from drill_sim.control.closed_loop import run_loop
from drill_sim.control.evaluation import LoopSettings
from drill_sim.control.reference import reference_gains
from drill_sim.core import load_preset
from drill_sim.session.scenario import Scenario

STICKS, CURED_STICK, CURED_SATURATION, CURED_SSI_RATIO = 0.20, 0.01, 0.05, 0.75


def one(job: tuple[str, float, float, str, str, float]) -> tuple:
    """(rpm, wob, profile, law, ssi, stick, saturation) of one run."""
    preset_name, rpm, wob, profile, law, duration = job
    preset = load_preset(preset_name)
    gains = reference_gains(law, preset, preset.top_drive.top_drive_inertia_kg_m2,
                            string_model="distributed", sensor_profile=profile)
    settings = LoopSettings(law=law, gains=gains, string_model="distributed",
                            sensor_profile=profile)
    r = run_loop(preset, Scenario.steady(rpm, wob, duration_s=duration,
                                         window_start_s=duration / 2), settings)
    return rpm, wob, profile, law, r.ssi, r.stick_fraction, r.saturation_fraction


def verdict(kin: tuple, zt: tuple) -> str:
    """'-' no stick-slip to cure, 'cured', or 'not cured'."""
    if kin[5] < STICKS:
        return "-"
    ok = (zt[5] <= CURED_STICK and zt[6] < CURED_SATURATION
          and zt[4] <= CURED_SSI_RATIO * kin[4])
    return "cured" if ok else "not cured"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", default="long")
    ap.add_argument("--rpm", default="40,55,70,100")
    ap.add_argument("--wob-kn", default="80,100,120,160")
    ap.add_argument("--duration", type=float, default=60.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--plot", default=None)
    a = ap.parse_args()
    rpms = [float(x) for x in a.rpm.split(",")]
    wobs = [float(x) for x in a.wob_kn.split(",")]
    jobs = [(a.preset, r, w, p, law, a.duration) for r, w, p, law in itertools.product(
        rpms, wobs, ("ideal", "surface_rig"), ("kinematic", "z_torque"))]
    start, results = time.monotonic(), {}
    with ProcessPoolExecutor(a.workers) as pool:
        for k, res in enumerate(pool.map(one, jobs), 1):
            results[res[:4]] = res
            print(f"\r{k}/{len(jobs)} runs", end="", file=sys.stderr, flush=True)
    print(f"\r{len(jobs)} runs in {time.monotonic() - start:.0f} s", file=sys.stderr)
    print(f"preset {a.preset}, distributed string, {a.duration:g} s runs, metrics over the "
          "second half; kinematic drive -> Z-Torque (reference tuning)")
    print("| rpm | WOB kN | sensors | kinematic SSI / stick | Z-Torque SSI / stick / sat | "
          "verdict |")
    print("| --- | --- | --- | --- | --- | --- |")
    for r, w, p in itertools.product(rpms, wobs, ("ideal", "surface_rig")):
        kin, zt = results[(r, w, p, "kinematic")], results[(r, w, p, "z_torque")]
        print(f"| {r:g} | {w:g} | {p} | {kin[4]:.2f} / {kin[5]:.2f} | {zt[4]:.2f} / "
              f"{zt[5]:.2f} / {zt[6]:.2f} | {verdict(kin, zt)} |")
    if a.plot:
        _plot(a, rpms, wobs, results)
    return 0


def _plot(a, rpms, wobs, results) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    marks = {"-": ("o", "0.7"), "cured": ("s", "tab:green"), "not cured": ("x", "tab:red")}
    for ax, profile in zip(axes, ("ideal", "surface_rig"), strict=True):
        for r, w in itertools.product(rpms, wobs):
            kin, zt = results[(r, w, profile, "kinematic")], results[(r, w, profile, "z_torque")]
            m, c = marks[verdict(kin, zt)]
            ax.scatter(r, w, marker=m, color=c, s=80)
            ax.annotate(f"{kin[5]:.2f}→{zt[5]:.2f}", (r, w), textcoords="offset points",
                        xytext=(0, 8), ha="center", fontsize=7)
        ax.margins(x=0.08, y=0.15)
        ax.set_title(f"{a.preset}, {profile} sensors")
        ax.set_xlabel("top-drive speed [rpm]")
    axes[0].set_ylabel("available weight on bit W0 [kN]")
    fig.suptitle("stuck fraction, kinematic → Z-Torque: ■ cured, × not cured, ● no stick-slip")
    fig.tight_layout()
    fig.savefig(a.plot, dpi=110)


if __name__ == "__main__":
    sys.exit(main())
