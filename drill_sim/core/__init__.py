"""The physics core of drill_sim: the Richard-Germay-Detournay drilling model, no ROS inside.

Dimensionless inside (``Simulator``), SI at the boundary (``Rig``); msg_docs/model.md describes
the model. The names below load on first use, so a light module of the core (``stick_slip``,
read by the bag tools) does not load the numba kernels. No name here is also a module's name
(``stability()`` is imported from ``core.stability``): importing that module would replace it.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .metrics import Metrics
    from .parameters import Groups, ParameterError, RigParameters, Scales
    from .presets import Preset, load_preset, preset_names
    from .rig import Rig
    from .rig_sample import RPM, RigSample
    from .simulator import DEFAULT_DT, Simulator, StateView, Trajectory
    from .stability import NoSteadyDrilling, StabilityResult, SteadyState, steady_state
    from .string_geometry import StringGeometry, StringSection
    from .top_drive import DriveGroups, TopDriveParameters
    from .trajectory import SITrajectory

_HOMES = {
    "metrics": ("Metrics",),
    "parameters": ("Groups", "ParameterError", "RigParameters", "Scales"),
    "string_geometry": ("StringGeometry", "StringSection"),
    "presets": ("Preset", "load_preset", "preset_names"),
    "rig": ("Rig",),
    "rig_sample": ("RPM", "RigSample"),
    "simulator": ("DEFAULT_DT", "Simulator", "StateView", "Trajectory"),
    "stability": ("NoSteadyDrilling", "StabilityResult", "SteadyState", "steady_state"),
    "top_drive": ("DriveGroups", "TopDriveParameters"),
    "trajectory": ("SITrajectory",),
}
_HOME_OF = {name: module for module, names in _HOMES.items() for name in names}

__all__ = [
    "DEFAULT_DT", "RPM", "DriveGroups", "Groups", "Metrics", "NoSteadyDrilling", "ParameterError",
    "Preset", "Rig", "RigParameters", "RigSample", "SITrajectory", "Scales", "Simulator",
    "StabilityResult", "StateView", "SteadyState", "StringGeometry", "StringSection",
    "TopDriveParameters",
    "Trajectory", "load_preset", "preset_names", "steady_state",
]


def __getattr__(name: str) -> Any:
    module = _HOME_OF.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value
