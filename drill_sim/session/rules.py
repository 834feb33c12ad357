"""A rig session as the node runs it, without ROS: its settings, its initial state, which
commands it accepts and how run-time parameter changes reach the rig. The node and the
re-simulation of a recorded session (``drill_sim bag resim``) share these rules, so the
re-run does exactly what the node did.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING

from ..core.parameters import ParameterError, RigParameters
from ..core.rig import Rig
from ..core.string_geometry import StringGeometry, StringSection
from ..core.top_drive import TopDriveParameters
from ..core.well import Well

COMMAND_FRAMES = ("", "top_drive")        # frame_id accepted on commands
RIG_FIELDS = tuple(f.name for f in fields(RigParameters))
TOP_DRIVE_FIELDS = tuple(f.name for f in fields(TopDriveParameters))

if TYPE_CHECKING:
    from ..wire.cdr_decode import JointCommand


def rig_parameters(values: dict[str, object]) -> RigParameters:
    """RigParameters from parameter values (raises ParameterError naming a bad one)."""
    return RigParameters(**{name: values[name] for name in RIG_FIELDS})


def top_drive_parameters(values: dict[str, object]) -> TopDriveParameters:
    """TopDriveParameters from parameter values (motor_torque_rate_nm_s 0: no rate limit);
    a session recorded before the top drive had parameters keeps the seed's kinematic drive."""
    if "top_drive_mode" not in values:
        return TopDriveParameters()
    d = {name: values[name] for name in TOP_DRIVE_FIELDS}
    if d["motor_torque_rate_nm_s"] == 0:
        d["motor_torque_rate_nm_s"] = math.inf
    return TopDriveParameters(**d)


def steps_per_tick(tick_s: float, dt_s: float) -> int:
    """The fewest whole steps of at most ``dt_s`` [s] that make one tick of ``tick_s`` [s]."""
    return max(1, math.ceil(tick_s / dt_s * (1.0 - 1e-12)))


def step_s(p: dict[str, object]) -> float:
    """The session's integration step [s]: the largest divisor of the tick 1/``rate_hz`` that
    is not above ``dt_s``, so that every tick advances exactly 1/``rate_hz`` of simulated time
    (at 1000 Hz and ``dt_s`` 105 us: ten steps of 100 us) and the model's stability limit,
    which ``dt_s`` respects, still holds."""
    tick_s = 1.0 / p["rate_hz"]
    return tick_s / steps_per_tick(tick_s, p["dt_s"])


def tick_refusal(rate_hz: float, dt_s: float) -> str | None:
    """Why the session's step ``dt_s`` [s] (fixed at start) cannot make ticks of 1/``rate_hz``,
    or None: a tick must be a whole number of steps."""
    steps = rate_hz * dt_s
    n = round(1.0 / steps) if steps > 0 else 0
    if n >= 1 and abs(n * steps - 1.0) <= 1e-9:
        return None
    return (f"rate_hz = {rate_hz:g}: a tick 1/rate_hz must be a whole number of the session's "
            f"step {dt_s:.6g} s (chosen at start from rate_hz and dt_s); expected a rate whose "
            "tick is a whole number of steps, e.g. the start rate divided by a whole number")


def make_rig(p: dict[str, object], dt_s: float | None = None,
             geometry: StringGeometry | None = None, params: RigParameters | None = None
             ) -> Rig:
    """The rig of a session's parameters, not yet started; its step is ``step_s(p)`` unless
    ``dt_s`` [s] is given (a recorded session's own step). ``string_model`` (absent: lumped,
    as in sessions recorded before it existed) ``distributed`` needs ``geometry``, the
    preset's pipe (the node's) or the one a bag's ``string`` record kept (``bag resim``).
    ``params``: the rig's SI parameters as the caller holds them (a preset's), which ``p``'s
    entries then show; None: built from ``p``'s entries (a ROS parameter table, a bag)."""
    rig = Rig(rig_parameters(p) if params is None else params,
              dt_s=step_s(p) if dt_s is None else dt_s,
              stick_window_s=p["stick_slip_window_s"],
              hoist_speed_limit_m_s=p["hoist_speed_limit_m_s"],
              top_drive=top_drive_parameters(p),
              string_model=p.get("string_model", "lumped"), geometry=geometry)
    rig.set_hook_mode(*hook_settings(p))
    return rig


def hook_settings(p: dict[str, object]) -> tuple[str, float]:
    """(hook_mode, block_speed_m_s) of a session's parameters (a session recorded before the
    hook had a mode: force)."""
    return str(p.get("hook_mode", "force")), float(p.get("block_speed_m_s", 0.0))


def geometry_record(geometry: StringGeometry) -> dict[str, str]:
    """The pipe geometry as a bag's ``string`` metadata record (field -> exact text; the
    sections, if it has them, as a JSON list of their given fields)."""
    record = {}
    for f in fields(StringGeometry):
        value = getattr(geometry, f.name)
        if f.name == "sections":
            if value:
                record["sections"] = json.dumps([x.given() for x in value])
        elif f.name == "well":
            if value is not None:
                well = {"survey": [list(r) for r in value.survey],
                        "friction_static": value.friction_static,
                        "friction_dynamic": value.friction_dynamic}
                if value.formations:
                    well["formations"] = [f.given() for f in value.formations]
                record["well"] = json.dumps(well)
        elif value is not None:
            record[f.name] = repr(float(value))
    return record


def geometry_from_record(record: dict[str, str]) -> StringGeometry:
    """The geometry ``geometry_record`` wrote (ParameterError if it is not one)."""
    names = {f.name for f in fields(StringGeometry)}
    try:
        given: dict[str, object] = {k: float(v) for k, v in record.items()
                                    if k in names and k not in ("sections", "well")}
        if "sections" in record:
            given["sections"] = tuple(StringSection(**x) for x in json.loads(record["sections"]))
        if "well" in record:
            well = json.loads(record["well"])
            given["well"] = Well(survey=tuple(tuple(r) for r in well["survey"]),
                                 friction_static=well["friction_static"],
                                 friction_dynamic=well["friction_dynamic"],
                                 formations=tuple(well.get("formations", ())))
        return StringGeometry(**given)
    except (TypeError, ValueError, AttributeError, KeyError) as exc:
        raise ParameterError(f"string record {record!r}: not a pipe geometry ({exc})") from None


def start(rig: Rig, p: dict[str, object]) -> None:
    """Put the rig in the session's initial state (at start and on reset)."""
    speed = p["initial_top_drive_speed_rad_s"]
    hook = rig.params.submerged_weight_n - p["initial_weight_on_bit_n"]
    if hook < 0:
        raise ParameterError(f"initial_weight_on_bit_n = {p['initial_weight_on_bit_n']:g} "
                             f"exceeds the string's submerged weight "
                             f"{rig.params.submerged_weight_n:g} N")
    if p["initial_state"] == "steady":
        rig.start_steady(speed, hook, perturbation=p.get("initial_perturbation", 0.0))
    else:
        rig.start_at_rest(p["initial_gap_m"])


@dataclass(frozen=True)
class CommandRule:
    """Which field of a command message carries the command, and the parameter that limits it.

    The commands are TwistStamped/WrenchStamped messages, taken as their six float64 in message
    order (linear or force x, y, z, then angular or torque x, y, z); ``index`` is the field's
    place among them, ``slot`` the argument of ``Rig.command`` it sets (0 speed, 1 hook load)."""

    what: str            # for refusals
    field: str           # message field path
    index: int
    slot: int            # 2: the motor torque (``Rig.command_motor_torque``)
    limit: str | float   # parameter (or a fixed value): the largest value accepted
    unit: str
    signed: bool = False         # accepted in [-limit, limit], not [0, limit]
    mode: str = ""               # the top_drive_mode it needs ("" any)


MOTOR_TORQUE_COMMAND_LIMIT_NM = 1e6       # |motor torque command|: beyond any top drive
JOINT_COMMANDS = "joint_commands"         # the rule of sensor_msgs/JointState commands
COMMANDS = {
    "top_drive": CommandRule("top-drive speed", "twist.angular.z", 5, 0,
                             "max_top_drive_speed_rad_s", "rad/s"),
    "hook_load": CommandRule("hook load", "wrench.force.z", 2, 1, "max_hook_load_n", "N"),
    "top_drive_torque": CommandRule("motor torque", "wrench.torque.z", 5, 2,
                                    MOTOR_TORQUE_COMMAND_LIMIT_NM, "N m", signed=True,
                                    mode="torque"),
}
# a JointState command: (joint, array) -> the rule its value goes through
JOINT_RULES = {("top_drive", "velocity"): "top_drive", ("top_drive", "effort"): "top_drive_torque",
               ("hook", "effort"): "hook_load"}


Refusal = tuple[str, object, str]          # (what, value, expected)


def command_refusal(frame_id: str, value: float, high: float, what: str, unit: str,
                    low: float = 0.0) -> Refusal | None:
    """Why a command is refused, as (what, value, expected), or None if it is used: the frame
    must be one of COMMAND_FRAMES and the value finite in [low, high]."""
    if frame_id not in COMMAND_FRAMES:
        return f"{what} frame_id", frame_id, "'top_drive' or empty"
    if not (math.isfinite(value) and low <= value <= high):
        return f"{what} [{unit}]", value, f"a finite value in [{low:g}, {high:g}] {unit}"
    return None


def _rule_refusal(p: dict[str, object], rule: CommandRule, frame_id: str, value: float,
                  what: str) -> Refusal | None:
    if rule.mode and p.get("top_drive_mode", "kinematic") != rule.mode:
        return (f"{what} (top_drive_mode is {p.get('top_drive_mode', 'kinematic')})", value,
                f"top_drive_mode = {rule.mode}: set the node's parameter first")
    high = p[rule.limit] if isinstance(rule.limit, str) else rule.limit
    return command_refusal(frame_id, value, high, what, rule.unit,
                           -high if rule.signed else 0.0)


def _hold(rig: Rig, rule: CommandRule, value: float) -> None:
    if rule.slot == 2:
        rig.command_motor_torque(value)
        return
    held = [rig.commanded_speed_rad_s, rig.commanded_hook_load_n]
    held[rule.slot] = value
    rig.command(*held)


def apply_command(rig: Rig, p: dict[str, object], name: str, frame_id: str,
                  six: Sequence[float] | JointCommand) -> Refusal | None:
    """Command ``name`` (a key of COMMANDS, or JOINT_COMMANDS with a JointCommand) arriving
    as ``six`` with ``frame_id``: held by the rig from now on if accepted (None), else the
    refusal as ``command_refusal`` gives it and the rig untouched. The node and the
    re-simulation of its bags both decide here."""
    if name == JOINT_COMMANDS:
        return _apply_joints(rig, p, frame_id, six)
    rule = COMMANDS[name]
    value = six[rule.index]
    refusal = _rule_refusal(p, rule, frame_id, value, f"{rule.what} {rule.field}")
    if refusal is None:
        _hold(rig, rule, value)
    return refusal


def _apply_joints(rig: Rig, p: dict[str, object], frame_id: str, j: JointCommand
                  ) -> Refusal | None:
    """A JointState command, taken whole or not at all: each (joint, velocity or effort) value
    goes through the rule of the topic that carries it (JOINT_RULES); unknown joints, a
    position, arrays whose length is neither 0 nor the number of names, or any value refused
    leave the rig untouched."""
    names = "'top_drive', 'hook'"
    if len(set(j.name)) != len(j.name) or not j.name:
        return "joint command name", list(j.name), f"distinct joint names among {names}"
    for n in j.name:
        if n not in ("top_drive", "hook"):
            return "joint command name", n, f"one of {names}"
    if j.position:
        return "joint command position", list(j.position), \
            "empty: the rig takes velocity (top_drive) and effort (top_drive, hook) only"
    values = []
    for array in ("velocity", "effort"):
        given = getattr(j, array)
        if not given:
            continue
        if len(given) != len(j.name):
            return (f"joint command {array} (for {len(j.name)} names)", list(given),
                    f"{len(j.name)} values, or none")
        for n, value in zip(j.name, given, strict=True):
            if (n, array) not in JOINT_RULES:
                return f"joint command {n} {array}", value, "none: hook takes effort only"
            rule = COMMANDS[JOINT_RULES[(n, array)]]
            refusal = _rule_refusal(p, rule, frame_id, value,
                                    f"joint command {n} {array} ({rule.what})")
            if refusal is not None:
                return refusal
            values.append((rule, value))
    if not values:
        return "joint command", list(j.name), "a velocity or an effort for each joint"
    for rule, value in values:
        _hold(rig, rule, value)
    return None


def apply_changes(rig: Rig, old: dict[str, object], new: dict[str, object]) -> set[str]:
    """Bring the rig to the parameter values ``new`` (from ``old``); the names that changed.
    Raises ParameterError, leaving the rig as it was, if the new values are refused."""
    changed = {k for k in new if new[k] != old.get(k)}
    if "rate_hz" in changed and (why := tick_refusal(new["rate_hz"], rig.dt_s)) is not None:
        raise ParameterError(why)
    old_drive, old_hook = rig.top_drive, (rig.hook_mode, rig.block_speed_m_s)
    try:
        if changed & {"hook_mode", "block_speed_m_s"}:
            rig.set_hook_mode(*hook_settings(new))
        if changed & set(TOP_DRIVE_FIELDS):
            rig.set_top_drive(top_drive_parameters(new))    # a change of mode is bumpless
        if changed & set(RIG_FIELDS):           # the rig's parameters with those changed
            rig.replace_parameters(replace(rig.params, **{k: new[k] for k in RIG_FIELDS
                                                          if k in changed}))
    except ParameterError:
        if rig.top_drive != old_drive:
            rig.set_top_drive(old_drive)
        if (rig.hook_mode, rig.block_speed_m_s) != old_hook:
            rig.set_hook_mode(*old_hook)
        raise
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
