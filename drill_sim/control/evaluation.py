"""The offline closed loop: a Rig stepped one controller sample period h at a time, a law on its
surface measurements, and the metrics that score it (msg_docs/control.md, "Evaluation").

Sample instants are those of the rig node at ``rate_hz = 1/h``: the rig steps with the
node's step, the largest divisor of h not above the default step (``core.session``: 100 µs at
1 kHz on base), so the samples fall exactly on k·h as the node's ticks do; the law reads
the sample there (through ``measure``, the sensor model; ideal by default) and its output is
held until the next sample (zero-order hold). So the same law at the same h gives
the same numbers here and through the nodes in lockstep.

Torque laws drive a top drive in ``torque`` mode (inertia, limits, rate and lag as given);
``kinematic`` drives the seed's ideal speed source. The law starts bumplessly from the steady
state at the scenario's first set-point, with a small speed perturbation that lets stick-slip
grow where it can.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from ..core import RPM, Preset, Rig, RigSample, load_preset
from ..core.parameters import ParameterError, check_number
from ..core.session import steps_per_tick
from ..core.simulator import DEFAULT_DT
from ..core.top_drive import TopDriveParameters
from . import make_law
from .laws import Law, SurfaceMeasurement
from .tuning import pipe_impedance

DEFAULT_SAMPLE_PERIOD_S = 1e-3     # the rig node's default rate_hz = 1000
DEFAULT_PERTURBATION = 1e-3        # relative bit-speed perturbation of the steady start

Measure = Callable[[RigSample], SurfaceMeasurement]


def ideal_measurement(sample: RigSample) -> SurfaceMeasurement:
    """The ideal sensor: the rig's values at the sample instant, no noise, no delay."""
    return SurfaceMeasurement(sample.time_s, sample.top_drive_speed_rad_s,
                              sample.motor_torque_nm, sample.surface_torque_nm)


def sensor_profiles() -> list[str]:
    """The sensor profiles a loop can measure through (``ideal`` alone before the core's
    sensor model exists)."""
    try:
        from ..core.sensor_profile import profile_names
    except ImportError:
        return ["ideal"]
    return profile_names()


def sensor_measurement(profile: str, sample_period_s: float, seed: int = 0) -> Measure:
    """The rig's sensor model (``core.sensors.SensorBank``) called once per controller sample,
    as the node calls it once per tick: a profile name or YAML path, seeded noise."""
    if profile == "ideal":
        return ideal_measurement
    try:
        from ..core.sensors import SensorBank
    except ImportError as exc:
        raise ParameterError(f"sensor_profile = {profile!r}: this build has no sensor model; "
                             "expected 'ideal'") from exc
    bank = SensorBank(profile, sample_period_s, seed)

    def measure(sample: RigSample) -> SurfaceMeasurement:
        m = bank.measure(sample.time_s, sample)
        return SurfaceMeasurement(sample.time_s, m.top_drive_speed_rad_s, m.motor_torque_nm,
                                  m.surface_torque_nm)
    return measure


@dataclass(frozen=True)
class Scenario:
    """Set-points against time: piecewise-linear (time [s], value) breakpoints, held after the
    last one. Metrics cover ``window_start_s`` .. ``duration_s`` (after the start's transient,
    or after a step: the "after" of a before/after). ``switch_on_s`` > 0: the drive's own stiff
    speed loop (``stiff_pi``, default gains) runs until then and the law takes over bumplessly
    (a controller switched on in stick-slip); 0: the law from the start."""

    name: str
    rpm_points: tuple[tuple[float, float], ...]      # (time [s], top-drive speed set-point [rpm])
    wob_kn_points: tuple[tuple[float, float], ...]   # (time [s], available weight W0 [kN])
    duration_s: float = 60.0
    window_start_s: float = 30.0
    switch_on_s: float = 0.0
    start_rpm: float | None = None     # the steady start's speed; None: the first set-point

    def __post_init__(self) -> None:
        check_number("duration_s", self.duration_s, high=1e5)
        check_number("switch_on_s", self.switch_on_s, low_inclusive=True, high=self.duration_s)
        check_number("window_start_s", self.window_start_s, low_inclusive=True,
                     high=self.duration_s)
        if not self.window_start_s < self.duration_s:
            raise ParameterError(f"window_start_s = {self.window_start_s!r} is out of range: "
                                 f"expected < duration_s = {self.duration_s!r}")
        for label, points in (("rpm_points", self.rpm_points),
                              ("wob_kn_points", self.wob_kn_points)):
            if not points:
                raise ParameterError(f"{label}: expected at least one (time_s, value) pair")
            times = [check_number(f"{label} time", t, low_inclusive=True) for t, _ in points]
            for _, v in points:
                check_number(f"{label} value", v, low=None)
            if any(b < a for a, b in itertools.pairwise(times)):
                raise ParameterError(f"{label}: times must not decrease, got {times}")

    @classmethod
    def steady(cls, rpm: float, wob_kn: float, *, name: str | None = None,
               duration_s: float = 60.0, window_start_s: float = 30.0,
               switch_on_s: float = 0.0) -> Scenario:
        """Constant set-points."""
        return cls(name or f"{rpm:g}rpm_{wob_kn:g}kN", ((0.0, rpm),), ((0.0, wob_kn),),
                   duration_s, window_start_s, switch_on_s)

    def values(self, time_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(speed set-point [rad/s], W0 [kN]) at these times."""
        def interp(points: tuple[tuple[float, float], ...]) -> np.ndarray:
            t, v = zip(*points, strict=True)
            return np.interp(time_s, np.asarray(t, float), np.asarray(v, float))
        return interp(self.rpm_points) * RPM, interp(self.wob_kn_points)


@dataclass(frozen=True)
class LoopSettings:
    """How the loop is closed: the law and its gains, h, the drive, the string, the sensor."""

    law: str
    gains: Mapping[str, float] = field(default_factory=dict)
    sample_period_s: float = DEFAULT_SAMPLE_PERIOD_S
    top_drive: TopDriveParameters | None = None     # None: the preset's (torque mode for laws)
    string_model: str = "lumped"
    perturbation: float = DEFAULT_PERTURBATION
    sensor_profile: str = "ideal"                   # ``sensor_profiles()``, or a YAML path
    sensor_seed: int = 0
    measure: Measure | None = None                  # overrides the profile (a custom sensor)


@dataclass
class LoopResult:
    """One closed-loop run's metrics over the window (units in the names) and its series at
    every sample (time [s], bit speed [rad/s], top-drive speed [rad/s], surface torque [N·m],
    motor torque applied [N·m], the law's output [N·m or rad/s], stuck flag)."""

    law: str
    scenario: str
    sensor_profile: str
    string_model: str
    ssi: float                        # (Ω_max − Ω_min)/(2 Ω_mean) of the bit speed, window
    stick_fraction: float             # time fraction with the bit stuck
    mean_rop_m_h: float               # mean rate of penetration [m/h]
    mean_bit_speed_rpm: float
    min_bit_speed_rpm: float
    max_bit_speed_rpm: float
    surface_torque_p2p_nm: float      # max − min of the surface (string) torque [N·m]
    surface_torque_rms_nm: float      # RMS of its deviation from the window mean [N·m]
    mean_surface_torque_nm: float
    saturation_fraction: float        # fraction of samples with the law's output on a limit
    saturation_time_s: float          # the same as time [s] (NaN: kinematic, no torque limit)
    mse_pa: float                     # mechanical specific energy, Teale [Pa]
    window_s: float                   # length of the metrics window [s]
    series: dict[str, np.ndarray] = field(repr=False, default_factory=dict)

    def row(self) -> dict[str, object]:
        """The metrics as a flat dict (for tables, CSV and JSON); mean_rop also as ``mean_rop``."""
        out: dict[str, object] = {k: v for k, v in self.__dict__.items() if k != "series"}
        out["mean_rop"] = self.mean_rop_m_h
        out["mse_mpa"] = self.mse_pa * 1e-6
        return out


def law_top_drive(preset: Preset, law_name: str,
                  top_drive: TopDriveParameters | None) -> TopDriveParameters:
    """The drive a law runs on: kinematic for ``kinematic``, torque mode for the others."""
    base = preset.top_drive if top_drive is None else top_drive
    mode = "kinematic" if law_name == "kinematic" else "torque"
    return replace(base, top_drive_mode=mode)


def build_law(preset: Preset, settings: LoopSettings, drive: TopDriveParameters) -> Law:
    """The law at h, its torque limits those of the drive unless the gains say otherwise."""
    gains = dict(settings.gains)
    if settings.law not in ("kinematic", "off"):
        gains.setdefault("torque_min_nm", drive.motor_torque_min_nm)
        gains.setdefault("torque_max_nm", drive.motor_torque_max_nm)
    return make_law(settings.law, settings.sample_period_s, pipe_impedance(preset),
                    drive.top_drive_inertia_kg_m2, **gains)


def run_loop(preset: Preset | str, scenario: Scenario, settings: LoopSettings, *,
             progress: Callable[[float], None] | None = None) -> LoopResult:
    """Close the loop over the scenario; see the module docstring for the sample instants."""
    preset = load_preset(preset) if isinstance(preset, str) else preset
    h = check_number("sample_period_s", settings.sample_period_s, high=1.0)
    drive = law_top_drive(preset, settings.law, settings.top_drive)
    law = build_law(preset, settings, drive)
    measure = settings.measure or sensor_measurement(settings.sensor_profile, h,
                                                     settings.sensor_seed)
    steps = steps_per_tick(h, DEFAULT_DT * preset.rig.scales.time_s)
    rig = Rig(preset.rig, h / steps, top_drive=drive, string_model=settings.string_model,
              geometry=preset.string)
    n = math.floor(scenario.duration_s / h + 1e-9)
    times = np.arange(n + 1) * h
    speed_set, wob_kn = scenario.values(times)
    hook = preset.rig.submerged_weight_n - 1e3 * wob_kn
    if np.any(hook < 0.0):
        raise ParameterError(f"wob_kn up to {wob_kn.max():g} kN is out of range: expected at "
                             f"most W_s = {preset.rig.submerged_weight_n / 1e3:g} kN")
    start = speed_set[0] if scenario.start_rpm is None else check_number(
        "start_rpm", scenario.start_rpm) * RPM
    rig.start_steady(float(start), float(hook[0]), perturbation=settings.perturbation)
    speed_law = law.output_kind == "speed"
    switch_k = 0 if speed_law else math.ceil(scenario.switch_on_s / h - 1e-9)
    active = law if switch_k == 0 else build_law(preset, replace(settings, law="stiff_pi",
                                                                  gains={}), drive)
    active.reset(float(speed_set[0]))
    law.reset(float(speed_set[0]))
    sample = rig.sample()
    current = rig.commanded_speed_rad_s if speed_law else rig.commanded_motor_torque_nm
    output = active.bumpless_start(current, measure(sample))
    names = ("time_s", "bit_speed_rad_s", "top_drive_speed_rad_s", "surface_torque_nm",
             "motor_torque_nm", "law_output", "stuck", "bit_depth_m", "top_drive_angle_rad",
             "wob_n")
    series = {k: np.empty(n + 1) for k in names}
    _record(series, 0, sample, output)
    window_k = max(1, math.ceil(scenario.window_start_s / h - 1e-9))
    every = max(1, n // 200)
    for k in range(1, n + 1):
        if speed_law:
            rig.command(output, float(hook[k - 1]))
        else:
            rig.command(float(speed_set[k - 1]), float(hook[k - 1]))
            rig.command_motor_torque(output)
        rig.advance_steps(steps)
        if k == window_k:
            rig.reset_metrics_window()
        sample = rig.sample()
        measurement = measure(sample)
        if k == switch_k:
            law.set_speed(float(speed_set[k]))
            output = law.bumpless_start(output, measurement)
            active = law
        else:
            active.set_speed(float(speed_set[k]))
            output = active.step(measurement)
        _record(series, k, sample, output)
        if progress is not None and k % every == 0:
            progress(k / n)
    return _result(preset, scenario, settings, drive, rig, series, window_k)


def _record(series: dict[str, np.ndarray], k: int, s: RigSample, output: float) -> None:
    series["time_s"][k] = s.time_s
    series["bit_speed_rad_s"][k] = s.bit_speed_rad_s
    series["top_drive_speed_rad_s"][k] = s.top_drive_speed_rad_s
    series["surface_torque_nm"][k] = s.surface_torque_nm
    series["motor_torque_nm"][k] = s.motor_torque_nm
    series["law_output"][k] = output
    series["stuck"][k] = s.stuck
    series["bit_depth_m"][k] = s.bit_depth_m
    series["top_drive_angle_rad"][k] = s.top_drive_angle_rad
    series["wob_n"][k] = s.wob_n


def _result(preset: Preset, scenario: Scenario, settings: LoopSettings,
            drive: TopDriveParameters, rig: Rig, series: dict[str, np.ndarray],
            window_k: int) -> LoopResult:
    m = rig.metrics()
    torque = series["surface_torque_nm"][window_k:]
    window_s = m["duration_s"]
    if settings.law == "kinematic":
        saturated = math.nan
    else:
        out = series["law_output"][window_k:]
        span = drive.motor_torque_max_nm - drive.motor_torque_min_nm
        tol = 1e-9 * span
        saturated = float(np.mean((out >= drive.motor_torque_max_nm - tol)
                                  | (out <= drive.motor_torque_min_nm + tol)))
    area = math.pi * preset.rig.bit_radius_m ** 2
    drilled_m = m["mean_rop_m_s"] * window_s
    mse = (m["mean_wob_n"] / area + m["work_top_drive_j"] / (area * drilled_m)
           if drilled_m > 0.0 else math.nan)
    return LoopResult(
        law=settings.law, scenario=scenario.name, sensor_profile=settings.sensor_profile,
        string_model=settings.string_model, ssi=m["ssi"], stick_fraction=m["stick_fraction"],
        mean_rop_m_h=m["mean_rop_m_s"] * 3600.0,
        mean_bit_speed_rpm=m["mean_bit_speed_rad_s"] / RPM,
        min_bit_speed_rpm=m["min_bit_speed_rad_s"] / RPM,
        max_bit_speed_rpm=m["max_bit_speed_rad_s"] / RPM,
        surface_torque_p2p_nm=float(torque.max() - torque.min()),
        surface_torque_rms_nm=float(torque.std()),
        mean_surface_torque_nm=m["mean_surface_torque_nm"],
        saturation_fraction=saturated, saturation_time_s=saturated * window_s,
        mse_pa=mse, window_s=window_s, series=series)


def sample_metrics(preset: Preset, series: Mapping[str, np.ndarray], window_start_s: float,
                   drive: TopDriveParameters | None, *, law: str, scenario: str,
                   sensor_profile: str = "ideal", string_model: str = "lumped") -> LoopResult:
    """The metrics of a loop from its samples alone (what a recording of the rig's topics
    holds), over the samples from ``window_start_s`` on: SSI and bit speeds of the samples,
    stick fraction of stuck samples, ROP from the bit's depth, saturation of the applied motor
    torque at the drive's limits (``drive`` None: none), MSE from the mean WOB and the string
    torque's work at the top, Σ T_s,k (Φ_TD,k+1 − Φ_TD,k). ``drill_sim control --ros`` scores
    with it; the offline loop's own metrics use the kernel's running integrals instead."""
    t = np.asarray(series["time_s"])
    w = t >= window_start_s - 1e-9
    speed = np.asarray(series["bit_speed_rad_s"])[w]
    torque = np.asarray(series["surface_torque_nm"])[w]
    depth = np.asarray(series["bit_depth_m"])[w]
    angle = np.asarray(series["top_drive_angle_rad"])[w]
    span = t[w][-1] - t[w][0]
    drilled = depth[-1] - depth[0]
    mean = float(speed.mean())
    if drive is None:
        saturated = math.nan
    else:
        motor = np.asarray(series["motor_torque_nm"])[w]
        tol = 1e-9 * (drive.motor_torque_max_nm - drive.motor_torque_min_nm)
        saturated = float(np.mean((motor >= drive.motor_torque_max_nm - tol)
                                  | (motor <= drive.motor_torque_min_nm + tol)))
    area = math.pi * preset.rig.bit_radius_m ** 2
    work = float(np.sum(torque[:-1] * np.diff(angle)))
    mse = (float(np.mean(np.asarray(series["wob_n"])[w][1:])) / area + work / (area * drilled)
           if drilled > 0.0 else math.nan)
    return LoopResult(
        law=law, scenario=scenario, sensor_profile=sensor_profile, string_model=string_model,
        ssi=float((speed.max() - speed.min()) / (2.0 * mean)) if mean > 0 else math.inf,
        stick_fraction=float(np.mean(np.asarray(series["stuck"])[w] > 0)),
        mean_rop_m_h=drilled / span * 3600.0 if span > 0 else math.nan,
        mean_bit_speed_rpm=mean / RPM, min_bit_speed_rpm=float(speed.min()) / RPM,
        max_bit_speed_rpm=float(speed.max()) / RPM,
        surface_torque_p2p_nm=float(torque.max() - torque.min()),
        surface_torque_rms_nm=float(torque.std()), mean_surface_torque_nm=float(torque.mean()),
        saturation_fraction=saturated, saturation_time_s=saturated * span, mse_pa=mse,
        window_s=float(span), series=dict(series))


def run_laws(preset: Preset | str, scenario: Scenario, laws: Sequence[str],
             base: LoopSettings | None = None, *,
             gains: Mapping[str, Mapping[str, float]] | None = None) -> list[LoopResult]:
    """Each law in turn on the same scenario and settings (gains per law name)."""
    base = base or LoopSettings(law="kinematic")
    gains = gains or {}
    return [run_loop(preset, scenario, replace(base, law=name, gains=gains.get(name, {})))
            for name in laws]
