"""What the offline closed loop (``closed_loop``) runs and how it is scored: the scenario's
set-points, the loop's settings, the sensors a law can read, and the metrics of a run
(msg_docs/control.md, "Evaluation"), also from a recording's samples alone (``sample_metrics``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from ..core import RPM, Preset, Rig, RigSample
from ..core.effort import Figures, effort_figures
from ..core.stick_slip import severity_index
from ..core.top_drive import TopDriveParameters
from ..session.scenario import Scenario
from . import LAWS, make_law
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
    """The sensor profiles a loop can measure through (the core's shipped ones)."""
    from ..core.sensor_profile import profile_names
    return profile_names()


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
    # the drive's effort and the settling over the window (``core.effort``; None: not applicable)
    motor_torque_rms_nm: float | None = None
    motor_torque_p2p_nm: float | None = None
    torque_rate_rms_nm_s: float | None = None
    time_at_torque_limit_fraction: float | None = None
    drive_energy_j: float | None = None
    settling_time_s: float | None = None
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
    return replace(base, top_drive_mode=LAWS[law_name].top_drive_mode)


def law_gains(settings: LoopSettings, drive: TopDriveParameters) -> dict[str, float]:
    """The law's gains, its torque limits those of the drive unless the gains say otherwise."""
    gains = dict(settings.gains)
    if LAWS[settings.law].limited_by_drive:
        gains.setdefault("torque_min_nm", drive.motor_torque_min_nm)
        gains.setdefault("torque_max_nm", drive.motor_torque_max_nm)
    return gains


def build_law(preset: Preset, settings: LoopSettings, drive: TopDriveParameters) -> Law:
    """The law at h, its torque limits those of the drive unless the gains say otherwise."""
    gains = law_gains(settings, drive)
    return make_law(settings.law, settings.sample_period_s, pipe_impedance(preset),
                    drive.top_drive_inertia_kg_m2, **gains)


def loop_result(preset: Preset, scenario: Scenario, settings: LoopSettings,
            drive: TopDriveParameters, rig: Rig, series: dict[str, np.ndarray],
            window_k: int) -> LoopResult:
    m = rig.metrics()
    torque = series["surface_torque_nm"][window_k:]
    window_s = m["duration_s"]
    if LAWS[settings.law].output_kind != "torque":
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
        mse_pa=mse, window_s=window_s, series=series,
        **_effort(series, window_k, drive, scenario))


def sample_metrics(preset: Preset, series: Mapping[str, np.ndarray], window_start_s: float,
                   drive: TopDriveParameters | None, *, law: str, scenario: str,
                   sensor_profile: str = "ideal", string_model: str = "lumped",
                   events_s: list[float] | None = None) -> LoopResult:
    """The metrics of a loop from its samples alone (what a recording of the rig's topics
    holds), over the samples from ``window_start_s`` on: SSI and bit speeds of the samples,
    stick fraction of stuck samples, ROP from the bit's depth, saturation of the applied motor
    torque at the drive's limits (``drive`` None: none), MSE from the mean WOB and the string
    torque's work at the top, Σ T_s,k (Φ_TD,k+1 − Φ_TD,k); the drive's effort and the
    settling after ``events_s`` (controller switch, set-point steps [s]) by ``core.effort``.
    ``drill_sim control --ros`` scores with it; the offline loop's own metrics use the
    kernel's running integrals instead."""
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
        ssi=severity_index(float(speed.max()), float(speed.min()), mean),
        stick_fraction=float(np.mean(np.asarray(series["stuck"])[w] > 0)),
        mean_rop_m_h=drilled / span * 3600.0 if span > 0 else math.nan,
        mean_bit_speed_rpm=mean / RPM, min_bit_speed_rpm=float(speed.min()) / RPM,
        max_bit_speed_rpm=float(speed.max()) / RPM,
        surface_torque_p2p_nm=float(torque.max() - torque.min()),
        surface_torque_rms_nm=float(torque.std()), mean_surface_torque_nm=float(torque.mean()),
        saturation_fraction=saturated, saturation_time_s=saturated * span, mse_pa=mse,
        window_s=float(span), series=dict(series),
        **_effort(series, int(np.argmax(w)), drive, events_s or []))


def _effort(series: Mapping[str, np.ndarray], window_k: int, drive: TopDriveParameters | None,
            events: Scenario | list[float]) -> Figures:
    """``core.effort``: the applied motor torque over the window, its limits unless the drive
    is kinematic or not known; the settling over the whole run, from its last event."""
    limited = drive is not None and drive.top_drive_mode != "kinematic"
    t = np.asarray(series["time_s"])
    return effort_figures(
        t, np.asarray(series["bit_speed_rad_s"]),
        np.asarray(series["motor_torque_nm"]) if "motor_torque_nm" in series else None,
        np.asarray(series["top_drive_speed_rad_s"]) if "top_drive_speed_rad_s" in series
        else None,
        torque_limits_nm=(drive.motor_torque_min_nm, drive.motor_torque_max_nm)
        if limited else None,
        events_s=events.settling_events_s if isinstance(events, Scenario) else events,
        window_start_s=float(t[window_k]) if t.size else 0.0)
