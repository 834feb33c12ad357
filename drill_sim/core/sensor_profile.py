"""Sensor profiles: what each measured quantity's sensor does to the model's exact value.

A profile is a YAML mapping (shipped ones in ``drill_sim/sensor_profiles/``; any file by path)
with ``description`` and ``channels``: for each measured quantity of ``CHANNELS`` its sample
rate, delay, noise, bias, quantisation and first-order filter (``ChannelSpec``). A channel the
profile leaves out is exact (every tick, no delay, no noise). Numbers are SI; noise, bias and
quantum are in the channel's own unit (its name says it). msg_docs/sensors.md documents the
keys and the shipped profiles with their sources.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from pathlib import Path

from .parameters import ParameterError
from .resources import read_yaml, shipped_names

PROFILE_FOLDER = "sensor_profiles"

# The measured quantities, in the bank's channel order: (name with unit, where it is measured).
# All but the severity read the RigSample field of the same name; the severity is computed
# downhole from the bit speed over a window (see sensors.SensorBank).
CHANNELS: tuple[str, ...] = (
    "surface_torque_nm",      # string torque at the top drive
    "top_drive_speed_rad_s",
    "motor_torque_nm",
    "hook_load_n",
    "wob_n",                  # downhole from here on
    "tob_nm",
    "bit_speed_rad_s",
    "stick_slip_severity",    # (max - min) / (2 mean) of the bit speed over window_s, no unit
)
SEVERITY = "stick_slip_severity"
DEFAULT_SEVERITY_WINDOW_S = 10.0
MAX_BUFFERED_SAMPLES = 1_000_000     # per channel: samples waiting out their delay


@dataclass(frozen=True)
class ChannelSpec:
    """One sensor. rate_hz: samples a second (None: every tick); delay_s: from sampling to
    showing [s]; noise_std / bias / quantum: white Gaussian noise's standard deviation, a
    constant offset and the quantisation step (0: none), in the channel's unit; filter_tau_s:
    time constant of the first-order low-pass before sampling [s] (0: none); window_s: the
    severity's analysis window [s] (severity channel only)."""

    rate_hz: float | None = None
    delay_s: float = 0.0
    noise_std: float = 0.0
    bias: float = 0.0
    quantum: float = 0.0
    filter_tau_s: float = 0.0
    window_s: float | None = None

    @property
    def period_s(self) -> float:
        """Sampling period [s]; 0 for every tick."""
        return 0.0 if self.rate_hz is None else 1.0 / self.rate_hz


@dataclass(frozen=True)
class SensorProfile:
    """A named set of sensors, one ``ChannelSpec`` per channel of ``CHANNELS``."""

    name: str
    description: str
    channels: dict[str, ChannelSpec]

    @property
    def severity_window_s(self) -> float:
        w = self.channels[SEVERITY].window_s
        return DEFAULT_SEVERITY_WINDOW_S if w is None else w

    def as_dict(self) -> dict:
        """Plain data (the form a YAML file has), for recording and JSON."""
        return {"description": self.description,
                "channels": {c: {k: v for k, v in asdict(s).items() if v is not None}
                             for c, s in self.channels.items()}}


_KEYS = tuple(f.name for f in fields(ChannelSpec))


def profile_names() -> list[str]:
    """The shipped profiles' names."""
    return shipped_names(PROFILE_FOLDER)


def load_profile(name_or_path: str | Path) -> SensorProfile:
    """A shipped profile by name (``ideal``, ``surface_rig``, ``mud_pulse``, ``wired_pipe``)
    or any profile YAML file; ParameterError saying what is wrong otherwise."""
    return profile_from_dict(*read_yaml("sensor profile", PROFILE_FOLDER, name_or_path))


def profile_from_dict(name: str, data: object) -> SensorProfile:
    """Validate a parsed profile: unknown keys, wrong types, NaN, negative times are refused
    with the profile, channel and key named and what was expected."""
    where = f"sensor profile {name!r}"
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ParameterError(f"{where}: expected a mapping with 'description' and 'channels', "
                             f"got {type(data).__name__}")
    unknown = set(data) - {"description", "channels"}
    if unknown:
        raise ParameterError(f"{where}: unknown key(s) {sorted(map(str, unknown))}; expected "
                             "description, channels")
    description = data.get("description", "")
    if not isinstance(description, str):
        raise ParameterError(f"{where}: description must be text")
    given = data.get("channels") or {}
    if not isinstance(given, dict):
        raise ParameterError(f"{where}: channels must be a mapping of channel name to sensor, "
                             f"got {type(given).__name__}")
    bad = set(given) - set(CHANNELS)
    if bad:
        raise ParameterError(f"{where}: unknown channel(s) {sorted(map(str, bad))}; expected "
                             f"some of {', '.join(CHANNELS)}")
    return SensorProfile(name, description,
                         {c: _channel(f"{where}, channel {c}", c, given.get(c)) for c in CHANNELS})


def _channel(where: str, channel: str, data: object) -> ChannelSpec:
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ParameterError(f"{where}: expected a mapping of {', '.join(_KEYS)}, "
                             f"got {type(data).__name__}")
    unknown = set(data) - set(_KEYS)
    if unknown:
        raise ParameterError(f"{where}: unknown key(s) {sorted(map(str, unknown))}; expected "
                             f"some of {', '.join(_KEYS)}")
    if "window_s" in data and channel != SEVERITY:
        raise ParameterError(f"{where}: window_s applies only to {SEVERITY}")
    values: dict[str, float | None] = {}
    for key, value in data.items():
        if value is None and key in ("rate_hz", "window_s"):
            values[key] = None
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value):
            raise ParameterError(f"{where}: {key} = {value!r}: expected a finite number, written "
                                 "as a YAML number (e.g. 1e9, 1.0e9 or 0.5; not quoted)")
        positive = key in ("rate_hz", "window_s")
        if key != "bias" and (value < 0 or (positive and value == 0)):
            raise ParameterError(f"{where}: {key} = {value!r}: expected a "
                                 f"{'positive' if positive else 'non-negative'} number"
                                 + (" (leave rate_hz out for every tick)"
                                    if key == "rate_hz" else ""))
        values[key] = float(value)
    spec = ChannelSpec(**values)
    if spec.rate_hz is not None and spec.delay_s * spec.rate_hz > MAX_BUFFERED_SAMPLES:
        raise ParameterError(f"{where}: delay_s = {spec.delay_s:g} s at rate_hz = "
                             f"{spec.rate_hz:g} would buffer more than {MAX_BUFFERED_SAMPLES:,} "
                             "samples; expected a shorter delay or a lower rate")
    return spec
