"""The physics core of drill_sim: the Richard-Germay-Detournay drilling model, no ROS inside.

Dimensionless inside (``Simulator``), SI at the boundary (``Rig``); msg_docs/model.md describes
the model.
"""

from .metrics import Metrics
from .parameters import Groups, ParameterError, RigParameters, Scales, StringGeometry
from .presets import Preset, load_preset, preset_names
from .rig import RPM, Rig, RigSample
from .simulator import DEFAULT_DT, Simulator, StateView, Trajectory
from .stability import NoSteadyDrilling, StabilityResult, SteadyState, stability, steady_state
from .top_drive import DriveGroups, TopDriveParameters
from .trajectory import SITrajectory

__all__ = [
    "DEFAULT_DT", "RPM", "DriveGroups", "Groups", "Metrics", "NoSteadyDrilling", "ParameterError",
    "Preset", "Rig", "RigParameters", "RigSample", "SITrajectory", "Scales", "Simulator",
    "StabilityResult", "StateView", "SteadyState", "StringGeometry", "TopDriveParameters",
    "Trajectory", "load_preset", "preset_names", "stability", "steady_state",
]
