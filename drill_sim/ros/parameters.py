"""The node's ROS parameters (the table: ``parameter_table``), declared so that a bad value at
start-up is one clear ``ParameterError`` (the node prints it and exits with status 2) rather
than rclpy's exception, and an integer where a real number is expected (``-p rate_hz:=1000``,
``ros2 param set ... rate_hz 500``) simply works.

Each parameter is declared with a dynamically typed descriptor, so rclpy takes any override;
the value is then checked and converted here, and the parameter gets its real descriptor
(type, range, read-only) with the converted value. At run time a pre-set callback converts
integers to reals (and whole reals to integers) before rclpy checks the type, and the node's
callback refuses, with the reason, what the table refuses."""

from __future__ import annotations

import difflib
from functools import partial

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, ParameterType
from rclpy.node import Node
from rclpy.parameter import Parameter

from ..core import ParameterError, Preset, load_preset
from ..session.parameter_table import (
    BOOL,
    FLOAT,
    INT,
    NAMES,
    PRESET_READ_ONLY,
    SPLITS,
    Spec,
    checked_change,
    cross_refusal,
    specs,
)
from ..session.scenario import Scenario, load_scenario
from ..session.scenario_player import checked_changes

_TYPES = {BOOL: ParameterType.PARAMETER_BOOL, INT: ParameterType.PARAMETER_INTEGER,
          FLOAT: ParameterType.PARAMETER_DOUBLE, str: ParameterType.PARAMETER_STRING,
          NAMES: ParameterType.PARAMETER_STRING_ARRAY}


def descriptor(spec: Spec) -> ParameterDescriptor:
    """The descriptor tools see: type, range, read-only, and the description with its unit."""
    unit = f" [{spec.unit}]" if spec.unit else ""
    d = ParameterDescriptor(name=spec.name, description=spec.description + unit,
                            read_only=bool(spec.read_only), type=_TYPES[spec.kind])
    if spec.kind is INT and spec.low is not None:
        d.integer_range = [IntegerRange(from_value=int(spec.low), to_value=int(spec.high),
                                        step=1)]
    elif spec.kind is FLOAT and spec.low is not None:
        d.floating_point_range = [FloatingPointRange(from_value=spec.low, to_value=spec.high,
                                                     step=0.0)]
    notes = [n for n in (f"0 or at least {spec.off_or_at_least:g}" if spec.off_or_at_least
                         else "", spec.why, spec.read_only) if n]
    d.additional_constraints = "; ".join(notes) if not spec.choices else \
        ("some of: " if spec.kind is NAMES else "one of: ") + ", ".join(spec.choices)
    return d


def _declare_any(node: Node, name: str, default: object, text: str) -> object:
    """Declare ``name`` taking whatever value the command line or params file gives."""
    return node.declare_parameter(name, default, ParameterDescriptor(
        description=text, dynamic_typing=True)).value


def declare(node: Node) -> tuple[Preset, dict[str, Spec], dict[str, object]]:
    """Declare ``preset``, then every parameter of that preset's table, on ``node``: the preset,
    the specs by name and the values. Raises ParameterError naming a value refused."""
    name = _declare_any(node, "preset", "base", "preset name or YAML file")
    if not isinstance(name, str):
        raise ParameterError(f"parameter preset = {name!r}: expected a preset name (base, "
                             "shallow, deep) or a preset YAML file")
    preset = load_preset(name)
    node.set_descriptor("preset", ParameterDescriptor(
        description="preset name (base, shallow, deep, long, field_a) or preset YAML file",
        read_only=True,
        type=ParameterType.PARAMETER_STRING, additional_constraints=PRESET_READ_ONLY))
    by_name = {s.name: s for s in specs(preset)}
    values: dict[str, object] = {}
    for spec in by_name.values():
        value, refusal = spec.check(_declare_any(node, spec.name, spec.default,
                                                 spec.description))
        if refusal is not None:
            raise ParameterError(f"parameter {refusal}")
        values[spec.name] = value
    if (refusal := cross_refusal(values)) is not None:
        raise ParameterError(f"parameters: {refusal}")
    for spec in by_name.values():
        node.set_descriptor(spec.name, descriptor(spec),
                            Parameter(spec.name, value=values[spec.name]).get_parameter_value())
    node.add_pre_set_parameters_callback(partial(_converted, node, by_name))
    return preset, by_name, values


def _converted(node: Node, by_name: dict[str, Spec], params: list[Parameter]
               ) -> list[Parameter]:
    """Integers for real parameters as reals, whole reals for integer ones as integers. A
    name the node never declared is refused by rclpy with a reason that does not name it
    ("Invalid access to undeclared parameter(s): []"): the node's log says which, and the
    nearest name it has."""
    out = []
    for param in params:
        if not node.has_parameter(param.name):
            near = difflib.get_close_matches(param.name, list(by_name), n=1, cutoff=0.6)
            node.get_logger().warning(
                f"set parameter '{param.name}' refused: {node.get_name()} has no such "
                "parameter" + (f"; did you mean '{near[0]}'?" if near else ""))
        spec = by_name.get(param.name)
        if spec is not None and param.type_ in (Parameter.Type.INTEGER, Parameter.Type.DOUBLE):
            value, _ = spec.check(param.value)
            if type(value) is not type(param.value):
                param = Parameter(param.name, value=value)
        out.append(param)
    return out


def refusal(by_name: dict[str, Spec], params: list[Parameter]) -> str | None:
    """Why a run-time change is refused, checked before rclpy's own checks (which would not
    say why): a parameter that cannot change, or a value the table refuses. None if neither."""
    for param in params:
        if param.name == "preset":
            return f"preset cannot change at run time: {PRESET_READ_ONLY}"
        spec = by_name.get(param.name)
        if spec is not None and spec.read_only:
            return f"{spec.name} cannot change at run time: {spec.read_only}"
        if spec is not None and (why := spec.check(param.value)[1]) is not None:
            return why
    return None


def changed(by_name: dict[str, Spec], values: dict[str, object], params: list[Parameter]
            ) -> tuple[dict[str, object], str | None]:
    """The values after a run-time change to ``params``, or the first refusal (a reason)."""
    new = dict(values)
    for param in params:
        if param.name in by_name:
            value, refusal = by_name[param.name].check(param.value)
            if refusal is not None:
                return values, refusal
            new[param.name] = value
    if (refusal := cross_refusal(new)) is not None:
        return values, refusal
    if not values["record"] and any(new[k] != values[k] for k in SPLITS):
        return values, "record_split_* apply to recording, and this node does not record " \
                       "(record is empty)"
    return new, None


def warn_unknown_given(node: Node) -> None:
    """A warning for each parameter given to ``node`` (``-p``, a params file) that it never
    declared, with the nearest name it has: ROS ignores such a parameter without a word, so
    a typo (``rate:=100``) would otherwise go unnoticed. QoS overrides are left alone."""
    given = getattr(node, "_parameter_overrides", {})      # rclpy's, as the node received them
    names = list(node.get_parameters_by_prefix(""))
    for name in sorted(n for n in given if not node.has_parameter(n)
                       and not n.startswith("qos_overrides.")):
        near = difflib.get_close_matches(name, names, n=1, cutoff=0.6)
        node.get_logger().warning(
            f"parameter '{name}' is not one of {node.get_name()}'s and is ignored"
            + (f": did you mean '{near[0]}'?" if near else " (none of its names is close)"))


def scenario_of(node: Node, p: dict[str, object], by_name: dict[str, Spec]
                ) -> tuple[Scenario | None, dict[str, object]]:
    """The scenario the node is to play (``scenario``; None without one) and the parameters
    it starts with, checked before anything runs (nothing recorded yet): the scenario loads,
    its ``initial_state`` is the node's (taken from the scenario when ``-p initial_state`` was
    not given, refused when it was and differs), and every change it makes is one the
    parameter table accepts. Raises ParameterError naming what is wrong."""
    if not p["scenario"]:
        return None, p
    where = f"parameter scenario = {p['scenario']!r}"
    try:
        scenario = load_scenario(str(p["scenario"]))
        if scenario.initial_state != p["initial_state"]:
            if "initial_state" in getattr(node, "_parameter_overrides", {}):
                raise ParameterError(
                    f"it is written for initial_state {scenario.initial_state}, and "
                    f"initial_state is {p['initial_state']}; expected -p initial_state:="
                    f"{scenario.initial_state} (or none: the scenario's is taken)")
            node.set_parameters([Parameter("initial_state", value=scenario.initial_state)])
            p = dict(p, initial_state=scenario.initial_state)
        checked_changes(scenario, p, partial(checked_change, by_name))
    except ParameterError as exc:
        raise ParameterError(f"{where}: {exc} (nothing was run)") from None
    return scenario, p
