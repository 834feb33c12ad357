"""Tuning helpers: the pipe's torsional impedance, the string's first mode, SoftSpeed gains.

Pure functions on the core's parameter objects (nothing here edits or runs the core). The
auto-tune estimates the stick-slip frequency from a measured surface-torque series as a rig
would: the dominant spectral peak of the detrended, windowed series, refined by parabolic
interpolation of the log-magnitude around the peak bin.
"""

from __future__ import annotations

import math
from functools import cache
from typing import NamedTuple

import numpy as np

from ..core.parameters import ParameterError, RigParameters, check_number
from ..core.presets import Preset, load_preset
from ..core.string_geometry import StringGeometry


class SoftSpeedGains(NamedTuple):
    """PI gains of SoftSpeed: T_m = K_p e + K_i ∫e + J_c dΩ_TD/dt."""

    kp_nm_s_rad: float               # K_p = k_p Z
    ki_nm_rad: float                 # K_i = (2π f_t)² (J_TD - J_c)
    tuning_frequency_hz: float       # f_t
    compensated_inertia_kg_m2: float  # J_c


def _geometry(source: Preset | StringGeometry | str) -> StringGeometry:
    if isinstance(source, str):
        source = load_preset(source)
    if isinstance(source, Preset):
        if source.string is None:
            raise ParameterError(f"preset {source.name!r} has no 'string' section: the pipe's "
                                 "impedance needs its geometry (OD, ID, G, rho)")
        return source.string
    if isinstance(source, StringGeometry):
        return source
    raise ParameterError(f"expected a Preset, StringGeometry or preset name, got "
                         f"{type(source).__name__}")


def pipe_impedance(source: Preset | StringGeometry | str) -> float:
    """Torsional characteristic impedance Z = J_p √(Gρ) of the drill pipe at the top drive
    (its top section) [N·m·s/rad].

    The torque a travelling wave carries per unit of angular speed: a top drive that looks
    like Z to the string absorbs every wave arriving from below.
    """
    return _geometry(source).torsional_impedance_nm_s_rad


@cache
def torsional_modes_hz(rig: RigParameters, geometry: StringGeometry,
                       top_drive_inertia_kg_m2: float | None, count: int = 5
                       ) -> tuple[float, ...]:
    """The pipe's first ``count`` torsional natural frequencies [Hz], off bottom, the BHA at
    the bottom and the drive's inertia at the top (None: kinematic, the top held); lossless
    (the damping moves them < 0.1 %). Cached: a root search takes ~0.5 s."""
    from ..core.distributed import geometry_waves
    from ..core.simulator import DEFAULT_DT
    from ..core.stability_distributed import natural_frequencies
    waves = geometry_waves(rig, geometry, DEFAULT_DT)
    top = (math.inf if top_drive_inertia_kg_m2 is None
           else top_drive_inertia_kg_m2 / rig.bha_inertia_kg_m2)
    torsional, _ = natural_frequencies(waves, rig.groups.psi, count, top_inertia=top)
    return tuple(float(w) / (2.0 * math.pi * rig.scales.time_s) for w in torsional)


def first_mode_frequency_hz(source: Preset | RigParameters | str,
                            top_drive_inertia_kg_m2: float | None = None, *,
                            string_model: str = "lumped") -> float:
    """The string's first torsional mode [Hz], off bottom, the f_t a SoftSpeed tuned from the
    model would use. ``top_drive_inertia_kg_m2=None`` means a kinematic top drive (speed
    imposed, infinite inertia).

    ``lumped``: √(C(1/I + 1/J_TD))/(2π), or √(C/I)/(2π) if kinematic. ``distributed``: the
    lowest root of the pipe's frequency equation with the BHA at the bottom and the drive's
    inertia at the top (``core.stability_distributed.natural_frequencies``; needs a preset's
    pipe geometry) -- the pipe's own inertia lowers it (base: 0.57 against 0.76 Hz).
    """
    if isinstance(source, str):
        source = load_preset(source)
    rig = source.rig if isinstance(source, Preset) else source
    if not isinstance(rig, RigParameters):
        raise ParameterError(f"expected a Preset, RigParameters or preset name, got "
                             f"{type(source).__name__}")
    if top_drive_inertia_kg_m2 is not None:
        top_drive_inertia_kg_m2 = check_number("top_drive_inertia_kg_m2",
                                               top_drive_inertia_kg_m2)
    if string_model == "distributed":
        return torsional_modes_hz(rig, _geometry(source), top_drive_inertia_kg_m2)[0]
    if string_model != "lumped":
        raise ParameterError(f"string_model = {string_model!r}: expected lumped or distributed")
    c, inertia = rig.torsional_stiffness_nm_per_rad, rig.bha_inertia_kg_m2
    inverse = 1.0 / inertia
    if top_drive_inertia_kg_m2 is not None:
        inverse += 1.0 / top_drive_inertia_kg_m2
    return math.sqrt(c * inverse) / (2.0 * math.pi)


def tune_soft_speed(impedance_nm_s_rad: float, top_drive_inertia_kg_m2: float, *,
                    f_t_hz: float = 0.2, kp_over_impedance: float = 4.0,
                    compensated_inertia_kg_m2: float = 0.0) -> SoftSpeedGains:
    """SoftSpeed gains: the PI's integral cancels the top's remaining inertia at f_t.

    At s = j2πf_t the drive's impedance (J_TD - J_c)s + K_p + K_i/s is then purely K_p = k_p Z:
    the top is a damper at the stick-slip frequency (Kyllingstad & Nessjøen, SPE 119660).
    """
    z = check_number("impedance_nm_s_rad", impedance_nm_s_rad)
    j_td = check_number("top_drive_inertia_kg_m2", top_drive_inertia_kg_m2)
    f_t = check_number("tuning_frequency_hz", f_t_hz, high=100.0)
    k_p = check_number("kp_over_impedance", kp_over_impedance, high=1000.0)
    j_c = check_number("compensated_inertia_kg_m2", compensated_inertia_kg_m2,
                       low_inclusive=True)
    if j_c >= j_td:
        raise ParameterError(f"compensated_inertia_kg_m2 = {j_c!r} is out of range: expected "
                             f">= 0 and < top_drive_inertia_kg_m2 = {j_td!r}")
    return SoftSpeedGains(kp_nm_s_rad=k_p * z, ki_nm_rad=(2.0 * math.pi * f_t) ** 2 * (j_td - j_c),
                          tuning_frequency_hz=f_t, compensated_inertia_kg_m2=j_c)


def dominant_frequency_hz(series: np.ndarray | list[float], h_s: float, *,
                          f_min_hz: float = 0.05, f_max_hz: float | None = None) -> float:
    """Frequency [Hz] of the largest spectral peak of a uniformly sampled series in a band.

    Linear trend removed (drilling torque drifts), Hann window, zero-padded to at least four
    times the length; the peak bin is refined by a parabola through the log-magnitudes of it
    and its neighbours, which puts a clean tone within a thousandth of a padded bin. A series
    without an oscillation about its trend is refused: it has no dominant frequency.
    """
    h_s = check_number("h_s", h_s)
    x = np.asarray(series, dtype=float)
    finite = int(np.count_nonzero(np.isfinite(x))) if x.ndim == 1 else 0
    if finite < 16 or finite < x.size:
        raise ParameterError(f"series: expected at least 16 finite samples, got {finite} of "
                             f"{x.size}")
    f_max = 0.5 / h_s if f_max_hz is None else check_number("f_max_hz", f_max_hz)
    f_min = check_number("f_min_hz", f_min_hz, low_inclusive=True)
    t = np.arange(x.size)
    scale = float(np.abs(x).max())
    x = x - np.polyval(np.polyfit(t, x, 1), t)
    if not float(np.abs(x).max()) > 1e-12 * scale:
        raise ParameterError("series: no oscillation once its linear trend is removed: "
                             "expected a torque that varies about its trend")
    n_fft = 1 << math.ceil(math.log2(4 * x.size))
    magnitude = np.abs(np.fft.rfft(x * np.hanning(x.size), n_fft))
    df = 1.0 / (n_fft * h_s)
    lo, hi = max(1, math.ceil(f_min / df)), min(magnitude.size - 2, int(f_max / df))
    if hi < lo:
        raise ParameterError(f"band {f_min:g}..{f_max:g} Hz holds no frequency bin of a "
                             f"{x.size * h_s:g} s record")
    k = lo + int(np.argmax(magnitude[lo:hi + 1]))
    a, b, c = np.log(magnitude[k - 1:k + 2] + 1e-300)
    curvature = a - 2.0 * b + c
    offset = 0.0 if curvature >= 0.0 else 0.5 * (a - c) / curvature
    return (k + offset) * df


def auto_tune_soft_speed(surface_torque_nm: np.ndarray | list[float], h_s: float,
                         impedance_nm_s_rad: float, top_drive_inertia_kg_m2: float, *,
                         f_min_hz: float = 0.05, f_max_hz: float = 5.0,
                         **gains: float) -> SoftSpeedGains:
    """SoftSpeed gains tuned at the dominant frequency of a recorded surface-torque series."""
    f_t = dominant_frequency_hz(surface_torque_nm, h_s, f_min_hz=f_min_hz, f_max_hz=f_max_hz)
    return tune_soft_speed(impedance_nm_s_rad, top_drive_inertia_kg_m2, f_t_hz=f_t, **gains)
