"""A rig session as the node runs it, without ROS: its settings, its initial state, which
commands it accepts and how run-time parameter changes reach the rig. The node and the
re-simulation of a recorded session (``drill_sim bag resim``) share these rules, so the
re-run does exactly what the node did.
"""

from __future__ import annotations

import math
from dataclasses import fields

from .parameters import ParameterError, RigParameters
from .rig import Rig

COMMAND_FRAMES = ("", "top_drive")        # frame_id accepted on commands
RIG_FIELDS = tuple(f.name for f in fields(RigParameters))


def rig_parameters(values: dict[str, object]) -> RigParameters:
    """RigParameters from parameter values (raises ParameterError naming a bad one)."""
    return RigParameters(**{name: values[name] for name in RIG_FIELDS})


def make_rig(p: dict[str, object]) -> Rig:
    """The rig of a session's parameters, not yet started."""
    return Rig(rig_parameters(p), dt_s=p["dt_s"], stick_window_s=p["stick_slip_window_s"],
               hoist_speed_limit_m_s=p["hoist_speed_limit_m_s"])


def start(rig: Rig, p: dict[str, object]) -> None:
    """Put the rig in the session's initial state (at start and on reset)."""
    speed = p["initial_top_drive_speed_rad_s"]
    hook = rig.params.submerged_weight_n - p["initial_weight_on_bit_n"]
    if hook < 0:
        raise ParameterError(f"initial_weight_on_bit_n = {p['initial_weight_on_bit_n']:g} "
                             f"exceeds the string's submerged weight "
                             f"{rig.params.submerged_weight_n:g} N")
    if p["initial_state"] == "steady":
        rig.start_steady(speed, hook)
    else:
        rig.start_at_rest(p["initial_gap_m"])


def command_refusal(frame_id: str, value: float, high: float, what: str, unit: str
                    ) -> tuple[str, object, str] | None:
    """Why a command is refused, as (what, value, expected), or None if it is used: the frame
    must be one of COMMAND_FRAMES and the value finite in [0, high]."""
    if frame_id not in COMMAND_FRAMES:
        return f"{what} frame_id", frame_id, "'top_drive' or empty"
    if not (math.isfinite(value) and 0.0 <= value <= high):
        return f"{what} [{unit}]", value, f"a finite value in [0, {high:g}] {unit}"
    return None


def apply_changes(rig: Rig, old: dict[str, object], new: dict[str, object]) -> set[str]:
    """Bring the rig to the parameter values ``new`` (from ``old``); the names that changed.
    Raises ParameterError, leaving the rig as it was, if the new values are refused."""
    changed = {k for k in new if new[k] != old.get(k)}
    if changed & set(RIG_FIELDS):
        rig.replace_parameters(rig_parameters(new))
    if "stick_slip_window_s" in changed:
        rig.set_stick_window(new["stick_slip_window_s"])
    if "hoist_speed_limit_m_s" in changed:
        rig.set_hoist_speed_limit(new["hoist_speed_limit_m_s"])
    return changed


def parse_value(text: str) -> object:
    """A parameter value back from its recorded text (bool, int, float or str)."""
    if text in ("True", "False"):
        return text == "True"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text
