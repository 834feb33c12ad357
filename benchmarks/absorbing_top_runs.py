"""The sticking points of the control map run with a top that reflects nothing
(msg_docs/control.md, "The control map"): the top drive's motor turns its inertia, within its
torque limits, so that the top sends down a fixed torsional invariant whatever the string sends
up (``StringSimulator.absorb_at_top``), the ideal of a law that damps the string's waves at the
top, with no filter, sensor or sample. A slow loop holds its mean speed (every 10 ms the level
is the top torque low-passed over ``--tau`` seconds plus Z times the set speed and the speed
error's integral over ``--tau``). Where even this top keeps sticking, no law acting by
absorbing the waves at the top cures the point; the kinematic drive beside it for reference.
Each point is run from 40 steady starts (``CURABILITY_STARTS``) and the stuck fractions
averaged (mean +- standard error); the absorbing top both ideal (no torque limit) and within
the motor's limits. Near the border one start's stuck fraction is a draw, and five starts'
mean too: at long's 40 rpm / 120 kN within the limits five starts gave 0.00 and forty give
0.014 +- 0.005. The rig steps as the control map's offline loop does (``loop_step_s``: its
1 ms tick in whole steps), so the two compare on one discretisation (a stuck fraction near
the border moves with the step too).

``--sensors PROFILE`` runs it instead as a law every 1 ms on that sensor profile's signals (b
estimated from the measured surface torque and speed), commanding the speed of a stiff source
and of the drive through its own speed loop.

Run: .venv/bin/python benchmarks/absorbing_top_runs.py [--preset long]
     [--points 40:120,40:160,55:160,70:160,100:160] [--duration 60] [--tau 10]
     [--starts 40] [--workers 2] [--sensors surface_rig]
"""

from __future__ import annotations

import argparse
import math
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

import numpy as np

from drill_sim.cli.checks import Number, in_range
from drill_sim.cli.errors import UsageError
from drill_sim.core import ParameterError, Preset, load_preset
from drill_sim.core import kernel as kn
from drill_sim.core.rig import Rig
from drill_sim.core.sensor_profile import load_profile
from drill_sim.core.sensors import SensorBank
from drill_sim.core.simulator import DEFAULT_DT
from drill_sim.session.rules import steps_per_tick

RPM = math.pi / 30.0
SAMPLE_S = 0.01
PERTURBATION = 1e-3          # the steady start's bit speed, as the control map's runs
STARTS = (1e-3, -1e-3, 3e-3, 1e-2, -1e-2)    # the perturbations averaged over: near the
                                             # border one run's stuck fraction is noisy
# the curability check's starts: +-1e-3 to +-2e-2 in steps of 1e-3 (STARTS among them). The
# absorbing top's runs are cheap (a 10 ms loop, about 0.25 s each), so its verdict is averaged
# over 40: at long's 40 rpm / 120 kN a start's stuck fraction within the limits scatters by
# 0.03, which leaves five starts' mean +-0.014, larger than the 1 % bar, and forty's +-0.005
CURABILITY_STARTS = tuple(sign * k * 1e-3 for k in range(1, 21) for sign in (1.0, -1.0))


def loop_step_s(preset: Preset) -> float:
    """The step [s] of the offline loop's rig (``drill_sim control``, the control map): the
    fewest whole steps of at most the model's default that make its 1 ms tick."""
    tick_s = 1e-3
    return tick_s / steps_per_tick(tick_s, DEFAULT_DT * preset.rig.scales.time_s)


class MeanSpeedLoop:
    """The absorbing top's slow loop: its level is the top torque low-passed over ``tau_s``
    plus Z times the set speed and 2/tau_s times the speed error's integral (any consistent
    units: the model's or SI)."""

    def __init__(self, torque: float, z: float, speed_set: float, tau_s: float,
                 period_s: float) -> None:
        self.torque, self.error = torque, 0.0
        self.z, self.speed_set, self.tau_s, self.period_s = z, speed_set, tau_s, period_s

    def level(self, torque: float, speed: float) -> float:
        """The level after one period with this top torque and speed."""
        self.torque += self.period_s / self.tau_s * (torque - self.torque)
        self.error += self.period_s * (self.speed_set - speed)
        return self.torque + self.z * (self.speed_set + 2.0 * self.error / self.tau_s)


def run(preset_name: str, rpm: float, wob_kn: float, absorbing: bool, duration_s: float,
        tau_s: float, limited: bool = True, perturbation: float = PERTURBATION
        ) -> tuple[float, float, float, float]:
    """(stuck fraction, SSI, mean top speed / set speed, share of the samples with the
    absorbing top's motor at a torque limit) over the run's second half (the rig's metrics,
    as the control map's)."""
    preset = load_preset(preset_name)
    drive = replace(preset.top_drive, top_drive_mode="kinematic")
    rig = Rig(preset.rig, loop_step_s(preset), string_model="distributed",
              geometry=preset.string,
              top_drive=drive)
    rig.start_steady(rpm * RPM, preset.rig.submerged_weight_n - wob_kn * 1e3, perturbation)
    sim = rig.sim
    c, t_star = rig.scales.stiffness_nm_per_rad, rig.scales.time_s
    limits = ((drive.motor_torque_min_nm / c, drive.motor_torque_max_nm / c) if limited
              else (-math.inf, math.inf))
    z, om0 = sim.top_impedance, rig.omega0_of(rpm * RPM)
    loop = MeanSpeedLoop(float(sim._x[kn.X_TS]), z, om0, tau_s, SAMPLE_S)
    if absorbing:
        sim.absorb_at_top(loop.torque + z * om0, *limits)
    top, n, held = 0.0, 0, 0
    angle = float(sim._x[kn.X_PHI_TD])
    for k in range(1, round(duration_s / SAMPLE_S) + 1):
        rig.advance_to(k * SAMPLE_S)
        x = sim._x
        speed = (x[kn.X_PHI_TD] - angle) / (SAMPLE_S / t_star)      # over the sample
        angle = float(x[kn.X_PHI_TD])
        if absorbing:
            sim.absorb_at_top(loop.level(x[kn.X_TS], speed), *limits)
        if k == round(0.5 * duration_s / SAMPLE_S):
            rig.reset_metrics_window()
        elif k * SAMPLE_S > 0.5 * duration_s:
            top += speed
            n += 1
            held += not limits[0] < x[kn.X_TM] < limits[1]       # the motor at a limit
    metrics = rig.metrics()
    return (float(metrics["stick_fraction"]), float(metrics["ssi"]), top / n / om0,
            held / n if absorbing else 0.0)


def run_sampled(preset_name: str, rpm: float, wob_kn: float, profile: str, start: float,
                duration_s: float, tau_s: float, through_drive: bool,
                period_s: float = 1e-3) -> tuple[float, float]:
    """The absorbing top as a law: every ``period_s`` it reads the sensors of ``profile``,
    estimates the arriving invariant b = T - Z Omega from the measured surface torque and
    top-drive speed, and commands the top's speed (level - b)/(2 Z) of a stiff speed source
    (the kinematic drive), or of the preset's drive through its own PI speed loop
    (``through_drive``); the level's slow loop ``MeanSpeedLoop``, as ``run``'s. (stuck
    fraction, SSI) over the second half."""
    preset = load_preset(preset_name)
    mode = "speed" if through_drive else "kinematic"
    rig = Rig(preset.rig, loop_step_s(preset), string_model="distributed",
              geometry=preset.string,
              top_drive=replace(preset.top_drive, top_drive_mode=mode))
    hook = preset.rig.submerged_weight_n - wob_kn * 1e3
    rig.start_steady(rpm * RPM, hook, start)
    z = rig.sim.top_impedance * rig.scales.stiffness_nm_per_rad * rig.scales.time_s
    om0 = rpm * RPM
    bank = SensorBank(profile, period_s, seed=1)
    loop = MeanSpeedLoop(rig.sample().surface_torque_nm, z, om0, tau_s, period_s)
    n = round(duration_s / period_s)
    for k in range(1, n + 1):
        m = bank.measure(rig.time_s, rig.sample())
        b = m.surface_torque_nm - z * m.top_drive_speed_rad_s
        level = loop.level(m.surface_torque_nm, m.top_drive_speed_rad_s)
        rig.command(max((level - b) / (2.0 * z), 0.0), hook)
        rig.advance_to(k * period_s)
        if k == n // 2:
            rig.reset_metrics_window()
    metrics = rig.metrics()
    return float(metrics["stick_fraction"]), float(metrics["ssi"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("--preset", default="long", help="a shipped preset or a preset YAML file")
    ap.add_argument("--points", default="40:120,40:160,55:160,70:160,100:160",
                    help="rpm:kN, comma-separated")
    ap.add_argument("--duration", type=float, default=60.0,
                    help="each run [s], 1 to 3600; the metrics over its second half")
    ap.add_argument("--tau", type=float, default=10.0,
                    help="the mean-speed loop's time constant [s], above 0 and at most 3600")
    ap.add_argument("--starts", type=int, default=len(CURABILITY_STARTS),
                    help=f"steady starts averaged per point, 1 to {len(CURABILITY_STARTS)} "
                    "(the first of CURABILITY_STARTS; --sensors runs the five of STARTS)")
    ap.add_argument("--workers", type=int, default=2, help="processes, at least 1")
    ap.add_argument("--sensors", default=None, metavar="PROFILE",
                    help="run the absorbing top as a law on this sensor profile's signals "
                    "(every 1 ms; a stiff speed source, and the drive's own speed loop)")
    a = ap.parse_args()
    points = []
    for part in a.points.split(","):
        try:
            rpm, wob = (Number(v.strip()) for v in part.split(":"))
        except ValueError:
            ap.error(f"--points: {part!r} is not a point; expected rpm:kN, e.g. 40:120, "
                     "comma-separated")
        try:                             # as drill_sim control checks its --rpm and --wob-kn
            points.append((in_range(f"--points {part}: speed", rpm, 0.0, 300.0, unit="rpm",
                                    low_open=True),
                           in_range(f"--points {part}: weight", wob, 0.0, 1e4, unit="kN",
                                    low_open=True)))
        except UsageError as exc:
            ap.error(str(exc))
    if not 1.0 <= a.duration <= 3600.0:
        ap.error(f"--duration {a.duration:g}: expected 1 to 3600 s")
    if not 1 <= a.starts <= len(CURABILITY_STARTS):
        ap.error(f"--starts {a.starts}: expected 1 to {len(CURABILITY_STARTS)}")
    if a.workers < 1:
        ap.error(f"--workers {a.workers}: expected at least 1")
    if not 0.0 < a.tau <= 3600.0:
        ap.error(f"--tau {a.tau:g}: expected a time constant above 0 s and at most 3600 s")
    if a.sensors is not None:
        try:
            load_profile(a.sensors)
        except ParameterError as exc:
            ap.error(f"--sensors {a.sensors}: {exc}")
    try:
        load_preset(a.preset)
    except ParameterError as exc:
        ap.error(f"--preset {a.preset}: {exc}")
    if a.sensors is not None:
        sampled(a, points)
        return
    starts = CURABILITY_STARTS[:a.starts]
    print(f"preset {a.preset}, {a.duration:g} s runs, second half, mean ± standard error over "
          f"{len(starts)} starts (±1e-3 to ±{max(starts):g} of the bit's steady speed); the "
          f"absorbing top's mean-speed loop {a.tau:g} s")
    print("| rpm | WOB kN | kinematic: stuck | absorbing top, ideal: stuck | within the motor's "
          "limits: stuck | its motor at a limit |")
    print("| --- | --- | --- | --- | --- | --- |")
    with ProcessPoolExecutor(a.workers) as pool:
        for rpm, wob in points:
            runs = {kind: np.array(list(pool.map(_one, [
                (a.preset, rpm, wob, kind, a.duration, a.tau, start) for start in starts])))
                for kind in ("kinematic", "ideal", "limited")}
            stuck = {kind: mean_error(r[:, 0]) for kind, r in runs.items()}
            print(f"| {rpm:g} | {wob:g} | {stuck['kinematic']} | {stuck['ideal']} | "
                  f"{stuck['limited']} | {runs['limited'][:, 3].mean():.2f} |", flush=True)


def _one(job: tuple[str, float, float, str, float, float, float]) -> tuple[float, ...]:
    """``run`` of one (preset, rpm, kN, kind, duration, tau, start): kind ``kinematic``,
    ``ideal`` (the absorbing top without limits) or ``limited`` (within the motor's)."""
    preset, rpm, wob, kind, duration, tau, start = job
    return run(preset, rpm, wob, kind != "kinematic", duration, tau, kind == "limited", start)


def mean_error(values: np.ndarray) -> str:
    """'mean ± standard error' of a sample, to 3 decimals."""
    if values.size < 2:
        return f"{values.mean():.3f} (one start)"
    return f"{values.mean():.3f} ± {values.std(ddof=1) / math.sqrt(values.size):.3f}"


def sampled(a: argparse.Namespace, points: list[tuple[float, ...]]) -> None:
    """The absorbing law on ``a.sensors``' signals, on a stiff source and through the drive."""
    print(f"preset {a.preset}, {a.duration:g} s runs, second half, mean ± sd over the "
          f"{len(STARTS)} starts; the absorbing top as a law every 1 ms on {a.sensors} signals")
    print("| rpm | WOB kN | stiff speed source: SSI / stuck | through the drive's speed loop: "
          "SSI / stuck |")
    print("| --- | --- | --- | --- |")
    for rpm, wob in points:
        cells = []
        for through in (False, True):
            r = np.array([run_sampled(a.preset, rpm, wob, a.sensors, start, a.duration, a.tau,
                                      through) for start in STARTS])
            cells.append(f"{r[:, 1].mean():.2f} / {r[:, 0].mean():.2f} ± {r[:, 0].std():.2f}")
        print(f"| {rpm:g} | {wob:g} | {cells[0]} | {cells[1]} |", flush=True)


if __name__ == "__main__":
    main()
