"""Reference stick-slip controllers on surface measurements, no ROS (msg_docs/control.md).

``make_law(name, h_s, impedance_nm_s_rad, top_drive_inertia_kg_m2, **gains)`` builds one of
``LAWS`` with every gain validated; ``tuning`` computes Z, the first mode and SoftSpeed gains.
"""

from __future__ import annotations

from ..core.parameters import ParameterError
from .filters import FilteredDerivative, FirstOrderSection
from .laws import PI, Kinematic, Law, Off, SoftSpeed, StiffPI, SurfaceMeasurement
from .tuning import (
    SoftSpeedGains,
    auto_tune_soft_speed,
    dominant_frequency_hz,
    first_mode_frequency_hz,
    pipe_impedance,
    tune_soft_speed,
)
from .z_torque import ZTorque

DEFAULT_TOP_DRIVE_INERTIA_KG_M2 = 2900.0

LAWS: dict[str, type[Law]] = {
    "kinematic": Kinematic,
    "stiff_pi": StiffPI,
    "soft_speed": SoftSpeed,
    "z_torque": ZTorque,
    "off": Off,
}


def make_law(name: str, h_s: float, impedance_nm_s_rad: float,
             top_drive_inertia_kg_m2: float = DEFAULT_TOP_DRIVE_INERTIA_KG_M2,
             **gains: float) -> Law:
    """Build law ``name`` for sample period ``h_s`` [s]; unknown names and gains are refused.

    Every value is checked (finite, in range) by the law's constructor, which raises
    ParameterError (a ValueError) naming the parameter, its value and the allowed range.
    """
    cls = LAWS.get(name)
    if cls is None:
        raise ParameterError(f"law = {name!r} is unknown: expected one of {', '.join(LAWS)}")
    unknown = sorted(set(gains) - set(cls.GAINS))
    if unknown:
        allowed = ", ".join(cls.GAINS) or "none"
        raise ParameterError(f"law {name!r}: unknown gain(s) {unknown}; expected {allowed}")
    return cls(h_s, impedance_nm_s_rad, top_drive_inertia_kg_m2, **gains)


def default_gains(name: str) -> dict[str, float]:
    """The gains law ``name`` takes by default, those its constructor gives as numbers (the
    others, such as Z-Torque's K_p, it derives from the string and the drive)."""
    import inspect
    cls = LAWS[name]
    return {gain: float(p.default) for gain, p in inspect.signature(cls.__init__).parameters.items()
            if gain in cls.GAINS and isinstance(p.default, (int, float))
            and not isinstance(p.default, bool)}


__all__ = [
    "DEFAULT_TOP_DRIVE_INERTIA_KG_M2", "LAWS", "PI", "FilteredDerivative", "FirstOrderSection",
    "Kinematic", "Law", "Off", "ParameterError", "SoftSpeed", "SoftSpeedGains", "StiffPI",
    "SurfaceMeasurement", "ZTorque", "auto_tune_soft_speed", "default_gains",
    "dominant_frequency_hz", "first_mode_frequency_hz", "make_law", "pipe_impedance",
    "tune_soft_speed",
]
