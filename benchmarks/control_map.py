"""Where top-end control cures stick-slip on the distributed string: the kinematic drive against
Z-Torque's reference tuning (passive up to the fifth mode), over speed and weight, with ideal
and ``surface_rig`` sensors (msg_docs/control.md, "The control map").

    python benchmarks/control_map.py [--preset long] [--rpm 40,55,70,100] \\
        [--wob-kn 80,100,120,160] [--duration 60] [--starts 5] [--scored-starts 40] \\
        [--workers 2] [--plot map.png] [--gain alpha=0.2 ...]

Each point is ``drill_sim control --rpm R --wob-kn W --string-model distributed`` for the
kinematic drive and Z-Torque (the offline loop, 1 ms sample, metrics over the second half), run
from ``--starts`` steady starts (the perturbations of absorbing_top_runs.py) and averaged. A
point "sticks" where the kinematic drive is stuck >= 20 % of the time there; each point that
sticks is then scored over ``--scored-starts`` of the 40 ``CURABILITY_STARTS`` (all three runs
and the absorbing top's), since near the border one 60 s run's stuck fraction is a draw and
five starts' mean too (long 40 rpm / 120 kN, the absorbing top within the limits: 0.00 over
five, 0.014 +- 0.005 over forty; 100 rpm / 160 kN, Z-Torque with ``surface_rig`` and the
rule's gains, before long's commissioning: 0.00 over five, 0.014 over forty). It is "cured"
where Z-Torque there sticks <= 1 %, saturates < 5 % and its SSI is at most 0.75 of the
kinematic's (all means over the starts); it is "not curable"
where even the top that reflects nothing, within the drive's motor limits
(absorbing_top_runs.py), sticks over 1 % there (a crude top: a cure outranks it); "-": the
kinematic drive stuck under 20 %, not scored. Z-Torque's gains are its reference gains, with
the preset's commissioned ones for ``surface_rig``'s signals (long's: control.md,
"Commissioned on long"); ``--gain NAME=VALUE`` overrides one of them for both sensor sets (a
tuning to compare, e.g. field_a's α 0.2 in control.md).
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from absorbing_top_runs import CURABILITY_STARTS, STARTS, mean_error
from absorbing_top_runs import run as absorbing_run

from drill_sim.cli.checks import Number, in_range
from drill_sim.cli.errors import UsageError
from drill_sim.control.closed_loop import run_loop
from drill_sim.control.evaluation import LoopSettings, build_law, law_top_drive
from drill_sim.control.reference import check_commissioning, reference_gains
from drill_sim.control.z_torque import ZTorque
from drill_sim.core import ParameterError, Preset, load_preset
from drill_sim.session.scenario import Scenario

STICKS, CURED_STICK, CURED_SATURATION, CURED_SSI_RATIO = 0.20, 0.01, 0.05, 0.75
WOB_MAX_KN = 1e4             # as drill_sim control's --wob-kn
ABSORBING_TAU_S = 10.0       # the absorbing top's mean-speed loop, as absorbing_top_runs.py's


def gains_of(preset: Preset, law: str, profile: str,
             overrides: dict[str, float]) -> dict[str, float]:
    """The reference gains of ``law`` on the preset's distributed string for ``profile``'s
    signals, with ``overrides`` (``--gain``) for Z-Torque."""
    gains = reference_gains(law, preset, preset.top_drive.top_drive_inertia_kg_m2,
                            string_model="distributed", sensor_profile=profile)
    return {**gains, **overrides} if law == "z_torque" else gains


def one(job: tuple[str, float, float, str, str, float, float, dict[str, float]]) -> tuple:
    """(ssi, stick, saturation) of one run."""
    preset_name, rpm, wob, profile, law, duration, perturbation, overrides = job
    preset = load_preset(preset_name)
    gains = gains_of(preset, law, profile, overrides)
    settings = LoopSettings(law=law, gains=gains, string_model="distributed",
                            sensor_profile=profile, perturbation=perturbation)
    r = run_loop(preset, Scenario.steady(rpm, wob, duration_s=duration,
                                         window_start_s=duration / 2), settings)
    return r.ssi, r.stick_fraction, r.saturation_fraction


def absorbed(job: tuple[str, float, float, float, float]) -> float:
    """The stuck fraction of one run with the top that reflects nothing, within the drive's
    motor limits (absorbing_top_runs.py; its mean-speed loop 10 s)."""
    preset_name, rpm, wob, duration, perturbation = job
    return absorbing_run(preset_name, rpm, wob, True, duration, ABSORBING_TAU_S,
                         limited=True, perturbation=perturbation)[0]


def missed_bars(kin: tuple, zt: tuple) -> list[str]:
    """The cure's bars Z-Torque missed (none: cured)."""
    return [what for what, bad in (("stuck", zt[5] > CURED_STICK),
                                   ("saturated", zt[6] >= CURED_SATURATION),
                                   ("SSI", zt[4] > CURED_SSI_RATIO * kin[4])) if bad]


def verdict(kin: tuple, zt: tuple, absorbing_stuck: float | None) -> str:
    """'-' the kinematic drive stuck under 20 % (not scored); 'cured' where Z-Torque meets the
    bars; else 'not curable' where the absorbing top within the motor's limits sticks over the
    bar too (a crude top, so a cure outranks it), or 'not cured'."""
    if kin[5] < STICKS:
        return "-"
    if not missed_bars(kin, zt):
        return "cured"
    if absorbing_stuck is not None and absorbing_stuck > CURED_STICK:
        return "not curable"
    return "not cured"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("--preset", default="long", help="a shipped preset or a preset YAML file")
    ap.add_argument("--rpm", default="40,55,70,100",
                    help="top-drive speeds [rpm], comma-separated, each above 0 and at most 300")
    ap.add_argument("--wob-kn", default="80,100,120,160",
                    help="available weights on bit W0 [kN], comma-separated, each above 0 "
                    f"and at most {WOB_MAX_KN:g}")
    ap.add_argument("--duration", type=float, default=60.0,
                    help="each run [s], 2 to 3600; the metrics over its second half")
    ap.add_argument("--workers", type=int, default=2, help="processes, at least 1")
    ap.add_argument("--starts", type=int, default=len(STARTS),
                    help=f"steady starts averaged per point, 1 to {len(STARTS)}")
    ap.add_argument("--scored-starts", type=int, default=len(CURABILITY_STARTS),
                    help="steady starts averaged at each point that sticks, 1 to "
                    f"{len(CURABILITY_STARTS)} (the first of absorbing_top_runs.py's "
                    "CURABILITY_STARTS)")
    ap.add_argument("--plot", default=None,
                    help="a PNG of the map: each point's verdict for each sensor set")
    ap.add_argument("--gain", action="append", default=[], metavar="NAME=VALUE",
                    help="override one of Z-Torque's reference gains (with the preset's "
                    "commissioned ones), for both sensor sets, e.g. alpha=0.2 "
                    "(repeatable; units as in msg_docs/control.md)")
    a = ap.parse_args()
    rpms = _values(ap, "--rpm", a.rpm, 300.0, "rpm")
    wobs = _values(ap, "--wob-kn", a.wob_kn, WOB_MAX_KN, "kN")
    if not 1 <= a.starts <= len(STARTS):
        ap.error(f"--starts {a.starts}: expected 1 to {len(STARTS)}")
    if not 1 <= a.scored_starts <= len(CURABILITY_STARTS):
        ap.error(f"--scored-starts {a.scored_starts}: expected 1 to {len(CURABILITY_STARTS)}")
    if not 2.0 <= a.duration <= 3600.0:
        ap.error(f"--duration {a.duration:g}: expected 2 to 3600 s")
    if a.workers < 1:
        ap.error(f"--workers {a.workers}: expected at least 1")
    try:
        preset = load_preset(a.preset)
        check_commissioning(preset)
    except ParameterError as exc:
        ap.error(f"--preset {a.preset}: {exc}")
    if a.plot is not None:
        plot = Path(a.plot)
        if plot.suffix.lower() != ".png" or not plot.parent.is_dir():
            ap.error(f"--plot {a.plot}: expected a .png file in an existing directory")
    overrides = _overrides(ap, a.gain, preset)
    starts = STARTS[:a.starts]
    # the kinematic drive reads no sensor: one set of its runs serves both profiles
    keys = [(r, w, p, law) for r, w in itertools.product(rpms, wobs)
            for p, law in (("ideal", "kinematic"), ("ideal", "z_torque"),
                           ("surface_rig", "z_torque"))]
    done = _runs_of(a, keys, starts, overrides, {})
    n = len(starts)
    results = {key: (*key, *np.mean([done[key, s] for s in starts], axis=0)) for key in keys}
    sticking = [(r, w) for r, w in itertools.product(rpms, wobs)
                if results[(r, w, "ideal", "kinematic")][5] >= STICKS]
    # the points that stick, scored over many starts (the five among them run once): the
    # law's runs and the absorbing top's
    scored = CURABILITY_STARTS[:a.scored_starts]
    m = len(scored)
    again = [key for key in keys if key[:2] in sticking]
    done = _runs_of(a, again, scored, overrides, done)
    results.update({key: (*key, *np.mean([done[key, s] for s in scored], axis=0))
                    for key in again})
    for r, w in itertools.product(rpms, wobs):
        results[(r, w, "surface_rig", "kinematic")] = results[(r, w, "ideal", "kinematic")]
    stuck = _run_all(a, absorbed, [(a.preset, r, w, a.duration, start)
                                   for r, w in sticking for start in scored])
    stuck_at = {point: np.array(stuck[i * m:(i + 1) * m]) for i, point in enumerate(sticking)}
    absorbing = {point: float(runs.mean()) for point, runs in stuck_at.items()}
    commissioned = preset.commissioned("z_torque")
    print(f"preset {a.preset}, distributed string, {a.duration:g} s runs, metrics over the "
          f"second half, means over {_starts(n)} ({_starts(m)} where the kinematic drive "
          "sticks); kinematic drive -> Z-Torque (reference tuning"
          + (", z_torque commissioned for surface_rig: "
             + ", ".join(f"{k} {v:g}" for k, v in commissioned.items()) if commissioned else "")
          + "".join(f", {k} {v:g}" for k, v in overrides.items())
          + "); the absorbing top's stick: mean ± standard error")
    print("| rpm | WOB kN | sensors | kinematic SSI / stick | absorbing top within the "
          "motor's limits: stick | Z-Torque SSI / stick / sat | verdict |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for r, w, p in itertools.product(rpms, wobs, ("ideal", "surface_rig")):
        kin, zt = results[(r, w, p, "kinematic")], results[(r, w, p, "z_torque")]
        top = absorbing.get((r, w))
        top_cell = "-" if top is None else mean_error(stuck_at[(r, w)])
        said = verdict(kin, zt, top)
        if said == "not cured":
            said += f" ({', '.join(missed_bars(kin, zt))})"
        print(f"| {r:g} | {w:g} | {p} | {kin[4]:.2f} / {kin[5]:.2f} | {top_cell} | "
              f"{zt[4]:.2f} / {zt[5]:.3f} / {zt[6]:.3f} | {said} |")
    print(f"(-: the kinematic drive stuck under {STICKS:.0%}, not scored; cured: Z-Torque stuck "
          f"<= {CURED_STICK:.0%}, its output on a limit < {CURED_SATURATION:.0%} of the time and "
          f"its SSI <= {CURED_SSI_RATIO:g} of the kinematic's; not curable: the absorbing top "
          f"within the motor's limits stuck over {CURED_STICK:.0%})")
    if a.plot:
        _plot(a, rpms, wobs, results, absorbing)
    return 0


def _run_all(a: argparse.Namespace, fn: Callable, jobs: list) -> list:
    """``fn`` over ``jobs`` on ``a.workers`` processes, in order, with a count on a terminal."""
    begin, out = time.monotonic(), []
    if not jobs:
        return out
    with ProcessPoolExecutor(a.workers) as pool:
        for k, res in enumerate(pool.map(fn, jobs), 1):
            out.append(res)
            if sys.stderr.isatty():
                print(f"\r{k}/{len(jobs)} runs", end="", file=sys.stderr, flush=True)
    print(f"\r{len(jobs)} runs in {time.monotonic() - begin:.0f} s", file=sys.stderr)
    return out


def _runs_of(a: argparse.Namespace, keys: list[tuple], starts: tuple[float, ...],
             overrides: dict[str, float], done: dict[tuple, tuple]) -> dict[tuple, tuple]:
    """``done`` and the runs (ssi, stick, saturation) of every (key, start) it lacks."""
    todo = [(key, start) for key in keys for start in starts if (key, start) not in done]
    runs = _run_all(a, one, [(a.preset, *key, a.duration, start, overrides)
                             for key, start in todo])
    return {**done, **dict(zip(todo, runs, strict=True))}


def _starts(n: int) -> str:
    return f"{n} starts" if n > 1 else "1 start"


def _values(ap: argparse.ArgumentParser, name: str, text: str, top: float,
            unit: str) -> list[float]:
    """The comma-separated numbers of option ``name``, each above 0 and at most ``top``
    (``checks.in_range``, as ``drill_sim control`` checks one)."""
    try:
        return [in_range(name, Number(x.strip()), 0.0, top, unit=unit, low_open=True)
                for x in text.split(",")]
    except ValueError:
        ap.error(f"{name} {text}: expected comma-separated numbers")
    except UsageError as exc:
        ap.error(str(exc))


def _overrides(ap: argparse.ArgumentParser, items: list[str],
               preset: Preset) -> dict[str, float]:
    """``--gain`` NAME=VALUE items as Z-Torque gains, each checked by building the law with
    them as the runs will, on the preset's drive (its constructor names a bad value and the
    range it expects)."""
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or name not in ZTorque.GAINS:
            ap.error(f"--gain {item!r}: expected NAME=VALUE with NAME one of Z-Torque's gains "
                     f"({', '.join(ZTorque.GAINS)})")
        try:
            out[name] = float(Number(value.strip()))
        except ValueError:
            ap.error(f"--gain {item!r}: {value!r} is not a number")
    drive = law_top_drive(preset, "z_torque", None)
    for profile in ("ideal", "surface_rig"):
        settings = LoopSettings(law="z_torque", sensor_profile=profile, string_model="distributed",
                                gains=gains_of(preset, "z_torque", profile, out))
        try:
            build_law(preset, settings, drive)
        except ParameterError as exc:
            ap.error(f"--gain: {exc}")
    return out


def _plot(a, rpms, wobs, results, absorbing) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    marks = {"-": ("o", "0.7"), "cured": ("s", "tab:green"), "not cured": ("x", "tab:red"),
             "not curable": ("^", "0.25")}
    for ax, profile in zip(axes, ("ideal", "surface_rig"), strict=True):
        for r, w in itertools.product(rpms, wobs):
            kin, zt = results[(r, w, profile, "kinematic")], results[(r, w, profile, "z_torque")]
            m, c = marks[verdict(kin, zt, absorbing.get((r, w)))]
            ax.scatter(r, w, marker=m, color=c, s=80)
            ax.annotate(f"{kin[5]:.2f}→{zt[5]:.2f}", (r, w), textcoords="offset points",
                        xytext=(0, 8), ha="center", fontsize=7)
        ax.margins(x=0.08, y=0.15)
        ax.set_title(f"{a.preset}, {profile} sensors")
        ax.set_xlabel("top-drive speed [rpm]")
    axes[0].set_ylabel("available weight on bit W0 [kN]")
    fig.suptitle("stuck fraction, kinematic → Z-Torque: ■ cured, × not cured, ▲ not curable "
                 "from the top (this drive), ● kinematic stuck < 20 % (not scored)", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.plot, dpi=110)


if __name__ == "__main__":
    sys.exit(main())
