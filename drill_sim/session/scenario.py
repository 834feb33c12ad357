"""Driller scenarios: surface set points against time, as a driller would give them.

A scenario YAML has ``duration_s``, the rig ``initial_state`` it expects (``steady`` or
``rest``) and a list of ``points``; each point has ``at_s`` and sets one
or both channels: top-drive speed (``rpm`` or ``top_drive_speed_rad_s``) and load (``wob_kn``,
the available weight W0 = W_s - H0, or ``hook_load_kn``). With ``ramp: true`` the channels it sets
ramp linearly from their previous set point; otherwise they step at ``at_s``. An optional
``controller: {law: z_torque, on_at_s: 35.0}`` switches a reference stick-slip controller
(``drill_sim_controller``) on at that time: before it, the rig's drive runs its own speed loop.
``changes`` lists run-time parameter changes at simulated times, each a mapping with ``at_s``
and the rig node's parameters it sets (``{at_s: 4.0, intrinsic_specific_energy_pa: 1.3e8}``:
a harder formation from 4 s on).

A scenario is played by ``drill_sim_drive`` on the node's clock from outside, or by the rig
session itself (the node's ``scenario`` parameter): then every set-point, change and switch
lands on exactly the tick of its simulated time, in real time, at max speed and in lockstep
alike, and is recorded.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass
from pathlib import Path

from ..core.parameters import ParameterError, check_number
from ..core.resources import read_yaml, shipped_names
from ..core.rig import RPM

_KEYS = {"at_s", "rpm", "top_drive_speed_rad_s", "wob_kn", "hook_load_kn", "ramp"}


@dataclass(frozen=True)
class _Point:
    at_s: float
    value: float
    ramp: bool
    is_wob: bool = False      # load channel: value is W0 [N] rather than H0 [N]


@dataclass(frozen=True)
class ControllerSwitch:
    """A reference controller (``law``) switched on at ``on_at_s`` [s] of the scenario."""

    law: str
    on_at_s: float


@dataclass(frozen=True)
class Scenario:
    """Set points for the top-drive speed [rad/s] and the hook load [N] against time [s]."""

    name: str
    description: str
    duration_s: float
    initial_state: str          # the rig's initial_state this scenario is written for
    speed: tuple[_Point, ...]
    load: tuple[_Point, ...]
    controller: ControllerSwitch | None = None
    changes: tuple[tuple[float, dict[str, object]], ...] = ()   # (at [s], parameters), by time

    def commands_at(self, t_s: float, submerged_weight_n: float) -> tuple[float, float]:
        """(top-drive speed [rad/s], hook load [N]) at time ``t_s``; W0 set points use W_s."""
        speed = _value(self.speed, t_s, lambda p: p.value)
        hook = _value(self.load, t_s, lambda p: submerged_weight_n - p.value if p.is_wob
                      else p.value)
        return speed, max(hook, 0.0)


def _value(points: tuple[_Point, ...], t: float, value) -> float:
    i = bisect_right([p.at_s for p in points], t) - 1
    if i < 0:
        return value(points[0])
    if i + 1 < len(points) and points[i + 1].ramp:
        a, b = points[i], points[i + 1]
        f = (t - a.at_s) / (b.at_s - a.at_s)
        return value(a) + f * (value(b) - value(a))
    return value(points[i])


def scenario_names() -> list[str]:
    return shipped_names("scenarios")


def load_scenario(name_or_path: str | Path) -> Scenario:
    """A shipped scenario by name (``tag_bottom``, ``step_test``) or any scenario YAML file."""
    return scenario_from_dict(*read_yaml("scenario", "scenarios", name_or_path))


def scenario_from_dict(name: str, data: object) -> Scenario:
    if not isinstance(data, dict) or not isinstance(data.get("points"), list) \
            or not data["points"]:
        raise ParameterError(f"scenario {name!r}: expected a mapping with a non-empty list "
                             "'points' and 'duration_s'")
    duration = check_number(f"scenario {name!r} duration_s", data.get("duration_s"))
    speed: list[_Point] = []
    load: list[_Point] = []
    last = -math.inf
    for i, raw in enumerate(data["points"]):
        where = f"scenario {name!r} point {i}"
        if not isinstance(raw, dict) or set(raw) - _KEYS or "at_s" not in raw:
            raise ParameterError(f"{where}: expected a mapping with at_s and any of "
                                 f"{', '.join(sorted(_KEYS - {'at_s'}))}; got {raw!r}")
        at = check_number(f"{where} at_s", raw["at_s"], low_inclusive=True)
        if at <= last:
            raise ParameterError(f"{where}: at_s = {at:g} does not increase")
        last = at
        ramp = bool(raw.get("ramp", False))
        speeds = [k for k in ("rpm", "top_drive_speed_rad_s") if k in raw]
        loads = [k for k in ("wob_kn", "hook_load_kn") if k in raw]
        if len(speeds) > 1 or len(loads) > 1 or not speeds + loads:
            raise ParameterError(f"{where}: give at most one speed (rpm or "
                                 "top_drive_speed_rad_s) and one load (wob_kn or hook_load_kn)")
        for key in speeds:
            v = check_number(f"{where} {key}", raw[key], low_inclusive=True)
            speed.append(_Point(at, v * RPM if key == "rpm" else v, ramp))
        for key in loads:
            v = check_number(f"{where} {key}", raw[key], low_inclusive=True)
            load.append(_Point(at, 1e3 * v, ramp, is_wob=key == "wob_kn"))
    if not speed or not load:
        raise ParameterError(f"scenario {name!r}: needs at least one speed and one load point")
    initial = data.get("initial_state", "steady")
    if initial not in ("steady", "rest"):
        raise ParameterError(f"scenario {name!r}: initial_state = {initial!r}: expected steady "
                             "or rest")
    return Scenario(name, str(data.get("description", "")), duration, initial, tuple(speed),
                    tuple(load), _controller(name, data.get("controller"), duration),
                    _changes(name, data.get("changes", []), duration))


def _changes(name: str, raw: object, duration_s: float
             ) -> tuple[tuple[float, dict[str, object]], ...]:
    """The scenario's parameter changes, by time (their names and values are checked by the
    session that plays them, against the node's parameter table)."""
    if not isinstance(raw, list):
        raise ParameterError(f"scenario {name!r} changes: expected a list of mappings with "
                             f"at_s and parameters; got {raw!r}")
    out = []
    for i, change in enumerate(raw):
        where = f"scenario {name!r} change {i}"
        if not isinstance(change, dict) or "at_s" not in change or len(change) < 2:
            raise ParameterError(f"{where}: expected a mapping with at_s and one or more "
                                 f"parameters; got {change!r}")
        at = check_number(f"{where} at_s", change["at_s"], low_inclusive=True, high=duration_s)
        out.append((at, {k: v for k, v in change.items() if k != "at_s"}))
    return tuple(sorted(out, key=lambda c: c[0]))


CONTROLLER_LAWS = ("stiff_pi", "soft_speed", "z_torque", "off")


def _controller(name: str, raw: object, duration_s: float) -> ControllerSwitch | None:
    if raw is None:
        return None
    where = f"scenario {name!r} controller"
    if not isinstance(raw, dict) or set(raw) != {"law", "on_at_s"}:
        raise ParameterError(f"{where}: expected a mapping with law and on_at_s; got {raw!r}")
    if raw["law"] not in CONTROLLER_LAWS:
        raise ParameterError(f"{where}: law = {raw['law']!r}: expected one of "
                             f"{', '.join(CONTROLLER_LAWS)}")
    on = check_number(f"{where} on_at_s", raw["on_at_s"], low_inclusive=True, high=duration_s)
    return ControllerSwitch(str(raw["law"]), on)


HOLD = "hold"
FOREVER_S = 1e9                 # a hold without --duration: until stopped


def hold_scenario(rpm: float, wob_kn: float | None, hook_load_kn: float | None,
                  duration_s: float | None) -> Scenario:
    """A constant top-drive speed [rpm] and weight on bit W0 [kN] (or hook load H0 [kN]), for
    ``duration_s`` or until stopped. Raises ParameterError naming a bad value."""
    load = {"wob_kn": wob_kn} if wob_kn is not None else {"hook_load_kn": hook_load_kn}
    text = f"hold {rpm:g} rpm, " + (f"{wob_kn:g} kN on bit" if wob_kn is not None
                                    else f"{hook_load_kn:g} kN hook load")
    return scenario_from_dict(HOLD, {"description": text, "duration_s": duration_s or FOREVER_S,
                                     "points": [{"at_s": 0.0, "rpm": rpm, **load}]})
