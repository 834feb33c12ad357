"""Scenarios: surface set-points against time, a controller switch, run-time parameter changes
and a metrics window — one experiment, whoever runs it: the rig session itself (the node's
``scenario`` parameter), ``drill_sim_drive`` from outside, and the offline evaluation
(``drill_sim control``, ``control.evaluation``).

A scenario YAML has ``duration_s``, the rig ``initial_state`` it expects (``steady`` or
``rest``) and a list of ``points``; each point has ``at_s`` and sets one
or both channels: top-drive speed (``rpm`` or ``top_drive_speed_rad_s``) and load (``wob_kn``,
the available weight W0 = W_s - H0, or ``hook_load_kn``). With ``ramp: true`` the channels it sets
ramp linearly from their previous set point; otherwise they step at ``at_s``. An optional
``controller: {law: z_torque, on_at_s: 35.0}`` switches a reference stick-slip controller
(``drill_sim_controller``) on at that time: before it, the rig's drive runs its own speed loop.
``changes`` lists run-time parameter changes at simulated times, each a mapping with ``at_s``
and the rig node's parameters it sets (``{at_s: 4.0, intrinsic_specific_energy_pa: 1.3e8}``:
a harder formation from 4 s on). ``window_start_s`` (optional) starts the metrics window of an
evaluation; without it, the window starts at the controller's switch, else at half the
duration.

Played by the rig session, every set-point, change and switch lands on exactly the tick of its
simulated time, in real time, at max speed and in lockstep alike, and is recorded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core.parameters import ParameterError, check_number
from ..core.resources import read_yaml, shipped_names
from ..core.rig_sample import RPM

_KEYS = {"at_s", "rpm", "top_drive_speed_rad_s", "wob_kn", "hook_load_kn", "ramp"}
_TOP_KEYS = {"description", "initial_state", "duration_s", "points", "controller", "changes",
             "window_start_s"}
# a point's unit -> its SI factor and channel
UNITS = {"rpm": RPM, "top_drive_speed_rad_s": 1.0, "wob_kn": 1e3, "hook_load_kn": 1e3}
DUE_TOLERANCE_S = 1e-9          # an event at a tick's time is due at that tick, rounding forgiven
UNDER_TEST = ""                 # a controller switch to the law an evaluation scores


def due(at_s: float, t_s: float) -> bool:
    """Whether an event at ``at_s`` [s] is due at a tick at ``t_s`` [s] of the scenario."""
    return at_s <= t_s + DUE_TOLERANCE_S


@dataclass(frozen=True)
class _Point:
    at_s: float
    value: float              # in its ``unit``
    ramp: bool
    unit: str                 # a key of UNITS


@dataclass(frozen=True)
class ControllerSwitch:
    """A reference controller (``law``; UNDER_TEST: the law an evaluation scores) switched on at
    ``on_at_s`` [s] of the scenario; before it the drive's own stiff speed loop runs."""

    law: str
    on_at_s: float


@dataclass(frozen=True)
class Scenario:
    """Set points for the top-drive speed and the load against time [s] (``commands_at`` in SI),
    a controller switch, parameter changes by time, and the metrics window of an evaluation."""

    name: str
    description: str
    duration_s: float
    initial_state: str          # the rig's initial_state this scenario is written for
    speed: tuple[_Point, ...]
    load: tuple[_Point, ...]
    controller: ControllerSwitch | None = None
    changes: tuple[tuple[float, dict[str, object]], ...] = ()   # (at [s], parameters), by time
    window_start_s: float | None = None   # metrics from here [s]; None: ``metrics_from_s``
    start_rpm: float | None = None        # a steady start's speed [rpm]; None: the first point's

    def __post_init__(self) -> None:
        check_number(f"scenario {self.name!r} duration_s", self.duration_s, high=1e9)
        if not self.speed or not self.load:
            raise ParameterError(f"scenario {self.name!r}: needs at least one speed and one "
                                 "load point")
        if self.window_start_s is not None:
            check_number(f"scenario {self.name!r} window_start_s", self.window_start_s,
                         low_inclusive=True, high=self.duration_s)
            if not self.window_start_s < self.duration_s:
                raise ParameterError(f"scenario {self.name!r}: window_start_s = "
                                     f"{self.window_start_s!r} is out of range: expected < "
                                     f"duration_s = {self.duration_s!r}")
        if self.start_rpm is not None:
            check_number(f"scenario {self.name!r} start_rpm", self.start_rpm)

    # ---- the evaluation's scenarios, built in code ---------------------------------------
    @classmethod
    def of_points(cls, name: str, rpm_points: tuple[tuple[float, float], ...],
                  wob_kn_points: tuple[tuple[float, float], ...], *, duration_s: float = 60.0,
                  window_start_s: float = 30.0, switch_on_s: float = 0.0,
                  start_rpm: float | None = None) -> Scenario:
        """Piecewise-linear (time [s], value) breakpoints, held after the last one: speed
        set-points [rpm], available weight W0 [kN]; ``switch_on_s`` > 0: the drive's stiff
        loop until then, the law under test after it (0: the law from the start)."""
        def points(label: str, pairs, unit: str) -> tuple[_Point, ...]:
            if not pairs:
                raise ParameterError(f"{label}: expected at least one (time_s, value) pair")
            out, last = [], -math.inf
            for t, v in pairs:
                t = check_number(f"{label} time", t, low_inclusive=True)
                if t < last:
                    raise ParameterError(f"{label}: times must not decrease, got "
                                         f"{[p[0] for p in pairs]}")
                last = t
                out.append(_Point(t, check_number(f"{label} value", v, low=None), True, unit))
            return tuple(out)
        duration_s = check_number("duration_s", duration_s, high=1e5)
        switch_on_s = check_number("switch_on_s", switch_on_s, low_inclusive=True,
                                   high=duration_s)
        return cls(name, "", duration_s, "steady", points("rpm_points", rpm_points, "rpm"),
                   points("wob_kn_points", wob_kn_points, "wob_kn"),
                   ControllerSwitch(UNDER_TEST, switch_on_s) if switch_on_s > 0.0 else None,
                   window_start_s=window_start_s, start_rpm=start_rpm)

    @classmethod
    def steady(cls, rpm: float, wob_kn: float, *, name: str | None = None,
               duration_s: float = 60.0, window_start_s: float = 30.0,
               switch_on_s: float = 0.0) -> Scenario:
        """Constant set-points."""
        return cls.of_points(name or f"{rpm:g}rpm_{wob_kn:g}kN", ((0.0, rpm),), ((0.0, wob_kn),),
                             duration_s=duration_s, window_start_s=window_start_s,
                             switch_on_s=switch_on_s)

    # ---- what it sets ---------------------------------------------------------------------
    @property
    def switch_on_s(self) -> float:
        """When the controller is switched on [s]; 0: no switch (the law from the start)."""
        return 0.0 if self.controller is None else self.controller.on_at_s

    def switch_on_sample(self, h_s: float) -> int:
        """The sample of period ``h_s`` [s] the controller steps first on: the first k with
        k h >= ``switch_on_s`` (0: no switch)."""
        return math.ceil(self.switch_on_s / h_s - 1e-9)

    @property
    def metrics_from_s(self) -> float:
        """The start of the metrics window [s]: ``window_start_s``, else the controller's
        switch, else half the duration."""
        if self.window_start_s is not None:
            return self.window_start_s
        return self.switch_on_s if self.switch_on_s > 0.0 else 0.5 * self.duration_s

    @property
    def settling_events_s(self) -> list[float]:
        """What a run settles after (``core.effort``): the controller's switch and every step
        of the speed set-point (a point that is no ramp and changes the value) [s]."""
        events = [self.controller.on_at_s] if self.controller is not None else []
        for before, p in zip(self.speed[:-1], self.speed[1:], strict=True):
            if not p.ramp and p.value * UNITS[p.unit] != before.value * UNITS[before.unit]:
                events.append(p.at_s)
        return sorted(events)

    @property
    def speed_is_constant(self) -> bool:
        return len({p.value * UNITS[p.unit] for p in self.speed}) == 1

    def commands_at(self, t_s: float, submerged_weight_n: float) -> tuple[float, float]:
        """(top-drive speed [rad/s], hook load [N], never negative) at time ``t_s`` [s]."""
        speed = float(_channel(self.speed, np.float64(t_s)))
        return speed, max(float(_hook(self.load, np.float64(t_s), submerged_weight_n)), 0.0)

    def speed_set_rad_s(self, time_s: np.ndarray) -> np.ndarray:
        """The top-drive speed set-point [rad/s] at these times [s]."""
        return _channel(self.speed, np.asarray(time_s, float))

    def values(self, time_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(speed set-point [rad/s], W0 [kN]) at these times; ParameterError for a load given
        as hook load (the evaluation sets weight on bit)."""
        if any(p.unit != "wob_kn" for p in self.load):
            raise ParameterError(f"scenario {self.name!r}: its load is a hook load: expected "
                                 "weight on bit (wob_kn) set-points for an evaluation")
        return _channel(self.speed, time_s), _interp(self.load, time_s, None)


def _interp(points: tuple[_Point, ...], t, value) -> np.ndarray:
    """The channel at times ``t``: linear between a ramp point and the one before it, held
    before a step (which takes effect at its time) and after the last point; ``value(p)``
    each point's value (None: as given)."""
    times, values = [], []
    for i, p in enumerate(points):
        v = p.value if value is None else value(p)
        if i and not p.ramp:
            times.append(p.at_s)             # held until the step ...
            values.append(values[-1])
        times.append(p.at_s)                 # ... which takes effect at its time
        values.append(v)
    return np.interp(t, times, values)


def _channel(points: tuple[_Point, ...], t) -> np.ndarray:
    """The speed channel [rad/s]: interpolated in its unit when the points share one."""
    units = {p.unit for p in points}
    if len(units) == 1:
        return _interp(points, t, None) * UNITS[units.pop()]
    return _interp(points, t, lambda p: p.value * UNITS[p.unit])


def _hook(points: tuple[_Point, ...], t, submerged_weight_n: float) -> np.ndarray:
    """The hook load [N]: W_s - W0 for weight-on-bit points."""
    units = {p.unit for p in points}
    if units == {"wob_kn"}:
        return submerged_weight_n - 1e3 * _interp(points, t, None)
    return _interp(points, t, lambda p: submerged_weight_n - 1e3 * p.value
                   if p.unit == "wob_kn" else 1e3 * p.value)


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
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise ParameterError(f"scenario {name!r}: unknown key(s) {unknown}: expected any of "
                             f"{', '.join(sorted(_TOP_KEYS))}")
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
            speed.append(_Point(at, check_number(f"{where} {key}", raw[key], low_inclusive=True),
                                ramp, key))
        for key in loads:
            load.append(_Point(at, check_number(f"{where} {key}", raw[key], low_inclusive=True),
                               ramp, key))
    if not speed or not load:
        raise ParameterError(f"scenario {name!r}: needs at least one speed and one load point")
    initial = data.get("initial_state", "steady")
    if initial not in ("steady", "rest"):
        raise ParameterError(f"scenario {name!r}: initial_state = {initial!r}: expected steady "
                             "or rest")
    return Scenario(name, str(data.get("description", "")), duration, initial, tuple(speed),
                    tuple(load), _controller(name, data.get("controller"), duration),
                    _changes(name, data.get("changes", []), duration),
                    window_start_s=data.get("window_start_s"))


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
