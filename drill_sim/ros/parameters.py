"""The node's ROS parameters: one table with type, default, range, unit and whether it may change
at run time. Model parameters default to the chosen preset's values."""

from __future__ import annotations

import math
from dataclasses import dataclass

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, ParameterType
from rclpy.node import Node
from rclpy.parameter import Parameter

from ..core import ParameterError, Preset, load_preset
from ..core.simulator import DEFAULT_DT


@dataclass(frozen=True)
class Spec:
    name: str
    default: object
    description: str
    low: float | None = None
    high: float | None = None
    read_only: bool = False
    choices: tuple[str, ...] = ()

    def refusal(self, value: object) -> str | None:
        """Why ``value`` is refused beyond what the descriptor's range enforces, or None."""
        if self.choices and value not in self.choices:
            return f"{self.name} = {value!r}: expected one of {', '.join(self.choices)}"
        if isinstance(value, float) and not math.isfinite(value):
            return f"{self.name} = {value!r} is not finite"
        return None

    def descriptor(self) -> ParameterDescriptor:
        d = ParameterDescriptor(name=self.name, description=self.description,
                                read_only=self.read_only)
        if isinstance(self.default, bool):
            d.type = ParameterType.PARAMETER_BOOL
        elif isinstance(self.default, int):
            d.type = ParameterType.PARAMETER_INTEGER
            if self.low is not None:
                d.integer_range = [IntegerRange(from_value=int(self.low), to_value=int(self.high),
                                                step=1)]
        elif isinstance(self.default, float):
            d.type = ParameterType.PARAMETER_DOUBLE
            if self.low is not None:
                d.floating_point_range = [FloatingPointRange(from_value=self.low,
                                                             to_value=self.high, step=0.0)]
        else:
            d.type = ParameterType.PARAMETER_STRING
            if self.choices:
                d.additional_constraints = "one of: " + ", ".join(self.choices)
        return d


MODEL_UNITS = {
    "bit_radius_m": ("bit radius a [m]", 1e-3, 1.0),
    "blade_count": ("number of blades n [-]", 1, 64),
    "intrinsic_specific_energy_pa": ("intrinsic specific energy epsilon [Pa]", 1e5, 1e10),
    "cutting_inclination": ("cutting-force inclination zeta [-]", 0.01, 10.0),
    "contact_stress_pa": ("wear-flat contact stress sigma [Pa]", 0.0, 1e10),
    "wear_flat_length_m": ("total wear-flat length l over all blades [m]", 0.0, 1.0),
    "friction_coefficient": ("bit-rock friction coefficient mu [-]", 0.0, 10.0),
    "wear_flat_orientation": ("wear-flat orientation number gamma [-]", 0.0, 10.0),
    "bha_mass_kg": ("BHA mass M [kg]", 1.0, 1e7),
    "bha_inertia_kg_m2": ("BHA polar inertia I [kg m^2]", 1e-3, 1e6),
    "torsional_stiffness_nm_per_rad": ("string torsional stiffness C [N m/rad]", 1.0, 1e8),
    "submerged_weight_n": ("submerged weight of the string W_s [N]", 1.0, 1e9),
}


def specs(preset: Preset) -> list[Spec]:
    """Every parameter but ``preset`` (declared first, since the others default from it)."""
    rig = preset.rig
    t_star = rig.scales.time_s
    out = [Spec(name, getattr(rig, name), text, low, high)
           for name, (text, low, high) in MODEL_UNITS.items()]
    out += [
        Spec("rate_hz", 1000.0, "tick rate of the stepping timer [Hz]", 1.0, 5000.0),
        Spec("real_time_factor", 1.0, "simulated seconds per wall second [-]", 0.01, 1000.0),
        Spec("max_speed", False, "with publish_clock: step as fast as possible"),
        Spec("publish_clock", False, "publish /clock with the simulation time (sim-time mode)"),
        Spec("dt_s", DEFAULT_DT * t_star, "fixed integration step [s]", 1e-7, 0.01,
             read_only=True),
        Spec("qos_reliability", "reliable", "reliability of every topic", read_only=True,
             choices=("reliable", "best_effort")),
        Spec("command_timeout_s", 1.0, "command age above which /diagnostics warns [s]",
             0.001, 3600.0),
        Spec("stick_slip_window_s", 4.0 * math.pi * t_star,
             "the stick-slip flag stays up this long after a stick [s]", 0.001, 3600.0),
        Spec("initial_state", "steady", "steady (drilling at the initial commands) or rest "
             "(at rest initial_gap_m above bottom, hanging, not rotating)",
             choices=("steady", "rest")),
        Spec("initial_top_drive_speed_rad_s", preset.top_drive_speed_rad_s,
             "top-drive speed command at start and after reset [rad/s]", 0.0, 100.0),
        Spec("initial_weight_on_bit_n", 1e3 * preset.weight_on_bit_kn,
             "available weight W0 = W_s - H0 at start and after reset [N]", 0.0, 1e9),
        Spec("initial_gap_m", 0.05, "with initial_state rest: bit height above bottom [m]",
             0.0, 100.0),
        Spec("max_top_drive_speed_rad_s", 30.0, "commands above this are refused [rad/s]",
             0.0, 1000.0),
        Spec("max_hook_load_n", 2.0 * rig.submerged_weight_n,
             "hook-load commands above this are refused [N]", 0.0, 1e10),
        Spec("hoist_speed_limit_m_s", 0.5, "the string rises no faster than this [m/s]",
             1e-4, 100.0),
        Spec("record", "", "bag directory to record the session into (rosbag2, MCAP); empty: "
             "no recording", read_only=True),
        Spec("record_split_duration_s", 0.0, "start a new bag file after this long [s]; 0: never",
             0.0, 1e7, read_only=True),
        Spec("record_split_size_bytes", 0, "start a new bag file past this size [bytes]; 0: never",
             0, 2**62, read_only=True),
        Spec("diagnostics_period_s", 1.0, "period of /diagnostics [s]", 0.05, 60.0,
             read_only=True),
    ]
    return out



def declare(node: Node) -> tuple[Preset, dict[str, Spec], dict[str, object]]:
    """Declare ``preset``, then every parameter of that preset's table, on ``node``: the preset,
    the specs by name and the values. Raises ParameterError naming a value refused."""
    node.declare_parameter("preset", "base", ParameterDescriptor(
        description="preset name (base, shallow, deep) or preset YAML file", read_only=True))
    preset = load_preset(node.get_parameter("preset").value)
    by_name = {s.name: s for s in specs(preset)}
    for spec in by_name.values():
        node.declare_parameter(spec.name, spec.default, spec.descriptor())
    values = {name: node.get_parameter(name).value for name in by_name}
    for name, spec in by_name.items():
        if (refusal := spec.refusal(values[name])) is not None:
            raise ParameterError(f"parameter {refusal}")
    return preset, by_name, values


def changed(by_name: dict[str, Spec], values: dict[str, object], params: list[Parameter]
            ) -> tuple[dict[str, object], str | None]:
    """The values after a run-time change to ``params``, or the first refusal (a reason)."""
    new = dict(values)
    for param in params:
        if param.name in new:
            refusal = by_name[param.name].refusal(param.value)
            if refusal is not None:
                return values, refusal
            new[param.name] = param.value
    return new, None
