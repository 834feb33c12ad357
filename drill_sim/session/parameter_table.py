"""The rig node's parameters as one table, without ROS: type (the default's), default, unit,
range with the reason for its bounds, and whether it may change at run time (and why not).
``ros.parameters`` declares them on the node; msg_docs/node.md documents each row, and
``tests/test_node_parameters.py`` checks the page against this table.

Physical parameters get the range a real rig can have, so that a run-time change inside its
range cannot turn the model absurd (a 1 GN string, 13 km of hole in 90 s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..core import Preset
from ..core.sensors import MAX_SENSOR_SEED
from ..core.simulator import DEFAULT_DT
from ..core.top_drive import MODES as TOP_DRIVE_MODES
from ..wire import rig_topics

MIB = 1 << 20
PERTURBATION_RANGE = (-0.9, 1.0)   # relative perturbation of the steady start's bit speed
BOOL, INT, FLOAT, STR, NAMES = bool, int, float, str, list
# the command topics a lockstep tick can wait for, as lockstep_topics names them
LOCKSTEP_CHOICES = tuple(t.name[2:] for t in rig_topics.COMMANDS)


@dataclass(frozen=True)
class Spec:
    """One parameter. ``read_only``: why it cannot change at run time ("" if it can);
    ``off_or_at_least``: 0 means off, other values must be at least this; ``why``: the reason
    for the bounds (refusals and msg_docs/node.md say it)."""

    name: str
    default: object
    description: str
    unit: str = ""
    low: float | None = None
    high: float | None = None
    why: str = ""
    read_only: str = ""
    choices: tuple[str, ...] = ()
    off_or_at_least: float | None = None

    @property
    def kind(self) -> type:
        return type(self.default)

    def expected(self) -> str:
        """What the parameter accepts, in words."""
        unit = f" {self.unit}" if self.unit else ""
        if self.kind is BOOL:
            return "true or false"
        if self.kind is STR:
            return "one of " + ", ".join(self.choices) if self.choices else "text"
        if self.kind is NAMES:
            return "a list of one or more of " + ", ".join(self.choices) + ", each once"
        what = "a whole number" if self.kind is INT else "a finite number"
        if self.low is None:
            return what
        low = self.low if self.off_or_at_least is None else self.off_or_at_least
        text = f"{what} from {_number(low, self.kind)} to {_number(self.high, self.kind)}{unit}"
        return text if self.off_or_at_least is None else "0 (off) or " + text

    def check(self, value: object) -> tuple[object, str | None]:
        """(the value in the parameter's type, None), or (value, why it is refused). Integers
        are taken for real numbers, and whole real numbers for integers."""
        kind = self.kind
        if kind is NAMES:
            return self._check_names(value)
        if kind is FLOAT and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        elif kind is INT and isinstance(value, float) and value.is_integer():
            value = int(value)
        ok = isinstance(value, kind) and (kind is BOOL or not isinstance(value, bool))
        if ok and kind is FLOAT:
            ok = math.isfinite(value)
        if ok and kind is STR:
            ok = not self.choices or value in self.choices
        if ok and kind in (INT, FLOAT) and self.low is not None:
            low = self.low
            if self.off_or_at_least is not None and value != 0:
                low = self.off_or_at_least
            ok = low <= value <= self.high
        if ok:
            return value, None
        return value, self._refusal(value)

    def _refusal(self, value: object) -> str:
        why = f" ({self.why})" if self.why else ""
        return f"{self.name} = {value!r}: expected {self.expected()}{why}"

    def _check_names(self, value: object) -> tuple[object, str | None]:
        """A list of names from ``choices`` (a single name is a list of one; a leading ``~/``
        is dropped), each once."""
        names = [value] if isinstance(value, str) else value
        if isinstance(names, (list, tuple)) and all(isinstance(n, str) for n in names):
            names = [n[2:] if n.startswith("~/") else n for n in names]
            if names and len(set(names)) == len(names) and set(names) <= set(self.choices):
                return names, None
        return value, self._refusal(value)


def _number(x: float, kind: type) -> str:
    return str(int(x)) if kind is INT else f"{x:g}"


# name: (description, unit, low, high, why the bounds)
MODEL = {
    "bit_radius_m": ("bit radius a", "m", 0.03, 0.45,
                     "drag and PDC bits are made from about 2 3/8 in to 36 in in diameter"),
    "intrinsic_specific_energy_pa": (
        "intrinsic specific energy epsilon of the rock", "Pa", 1e7, 5e8,
        "close to the rock's compressive strength: ~10 MPa for soft shales to ~500 MPa for "
        "the hardest quartzites"),
    "cutting_inclination": ("cutting-force inclination zeta", "", 0.3, 1.5,
                            "measured 0.5-0.9 on PDC cutters; wider for other rake angles"),
    "contact_stress_pa": ("wear-flat contact stress sigma", "Pa", 0.0, 5e8,
                          "of the order of the rock's strength, like epsilon"),
    "wear_flat_length_m": ("total wear-flat length l over all blades", "m", 0.0, 0.1,
                           "0 for a sharp bit; ~10 mm on a worn 8 1/2 in bit; 100 mm is a bit "
                           "worn far beyond pulling"),
    "friction_coefficient": ("bit-rock friction coefficient mu", "", 0.05, 1.5,
                             "rock on cutter under mud: ~0.1 lubricated to ~1 in dry hard rock"),
    "wear_flat_orientation": ("wear-flat orientation number gamma", "", 0.5, 2.0,
                              "a geometry number of the bit, ~1 to 4/3 for drag bits"),
    "bha_mass_kg": ("BHA mass M", "kg", 300.0, 2e5,
                    "a few slim collars (~0.5 t) to 300 m of 11 in collars (~190 t)"),
    "bha_inertia_kg_m2": ("BHA polar inertia I", "kg m^2", 0.1, 3000.0,
                          "slim BHAs (~1 kg m^2) to 300 m of 11 in collars (~1500 kg m^2)"),
    "torsional_stiffness_nm_per_rad": (
        "string torsional stiffness C = G J / L of the pipe", "N m/rad", 10.0, 1e5,
        "10 km of 2 7/8 in pipe (~10) to 100 m of 6 5/8 in pipe (~2e4)"),
    "submerged_weight_n": ("submerged weight of the string W_s", "N", 1e4, 5e6,
                           "1 t to 510 t in mud: the heaviest drill strings weigh 3-4 MN"),
}
BLADES = "drag bits have 2 to 4 blades, PDC bits 3 to about 12"
START_ONLY = "read at start-up; restart the node to change it"


def specs(preset: Preset) -> list[Spec]:
    """Every parameter but ``preset`` (declared first, since the others default from it)."""
    rig = preset.rig
    t_star = rig.scales.time_s
    out = [Spec(name, float(getattr(rig, name)), text, unit, low, high, why)
           for name, (text, unit, low, high, why) in MODEL.items()]
    out.insert(1, Spec("blade_count", int(rig.blade_count), "number of blades n", "", 2, 12,
                       BLADES, read_only="it sets the sector of the rock surface the model "
                       "keeps, so it cannot change while the node runs"))
    speed = "top drives turn at up to ~250-350 rpm (26-37 rad/s)"
    out += [
        Spec("rate_hz", 1000.0, "tick rate: each tick advances 1/rate_hz of simulated time",
             "Hz", 1.0, 5000.0,
             "one tick costs ~0.1-0.2 ms in rclpy"),
        Spec("real_time_factor", 1.0, "simulated seconds per wall second", "", 0.01, 1000.0),
        Spec("publish_clock", False, "publish /clock with the simulation time (sim-time mode)",
             read_only="it chooses the node's time: stamps from zero and /clock, or the wall "
             "clock; " + START_ONLY),
        Spec("max_speed", False, "with publish_clock: step as fast as possible",
             read_only="it chooses the node's tick loop; " + START_ONLY),
        Spec("string_model", preset.string_model, "the drill string's model: lumped (one "
             "torsional spring on the BHA) or distributed (the preset's pipe carrying torsional "
             "and axial waves, msg_docs/model.md); default the preset's",
             read_only="the model's state is made at start (bag resim re-runs it); "
             + START_ONLY, choices=("lumped", "distributed")),
        Spec("dt_s", DEFAULT_DT * t_star, "largest integration step; the step used is the "
             "largest divisor of the tick 1/rate_hz not above it", "s", 1e-7, 0.01,
             "the model's step must stay well below t* (0.21 s on base)",
             read_only="the step is fixed for a session (bag resim re-runs it); " + START_ONLY),
        Spec("lockstep", False, "with publish_clock: after each tick wait for a command "
             "stamped with its time on each of lockstep_topics, then advance (msg_docs/node.md, "
             "Lockstep)", read_only="it chooses the node's tick loop; " + START_ONLY),
        Spec("lockstep_topics", ["cmd/top_drive"], "the command topics a lockstep tick waits "
             "for", read_only="the wait is set up at start; " + START_ONLY,
             choices=LOCKSTEP_CHOICES),
        Spec("lockstep_timeout_s", 1.0, "a lockstep tick waiting longer than this warns and "
             "is published again (the rig keeps waiting)", "s", 0.01, 3600.0),
        Spec("scenario", "", "a driller scenario the rig plays itself on its simulated clock "
             "(a shipped name or a YAML file, msg_docs/driver.md): its set-points, parameter "
             "changes and controller switch land on exactly the tick of their time and are "
             "recorded; empty: none",
             read_only="the scenario starts with the session; " + START_ONLY),
        Spec("scenario_controller", "drill_sim_controller", "the controller node a "
             "scenario's controller switch asks (its law and enabled parameters; in lockstep "
             "the tick waits until it confirms); empty: the switch is only recorded",
             read_only="the switch's client is made at start; " + START_ONLY),
        Spec("start_paused", False, "start paused: nothing is published until ~/pause false, "
             "so a controller can connect before the first tick",
             read_only="it applies at start only"),
        Spec("thread_priority", 0, "real time and lockstep: the loop's thread under "
             "SCHED_FIFO at this priority (ticks on time on a shared machine; needs root, "
             "CAP_SYS_NICE or an rtprio limit, else a warning); 0: the default scheduler",
             "", 0, 99, "0 (off) or a SCHED_FIFO priority 1-99",
             read_only="the loop's thread is set at start; " + START_ONLY),
        Spec("cpu_wakeup_latency_us", -1, "while the node runs, no core of the machine may "
             "sleep in an idle state slower than this to wake (Linux's CPU latency QoS, "
             "/dev/cpu_dma_latency; 0: idle cores poll), so ticks and the controller's "
             "wake-ups come on time; the whole machine's setting, at the price of idle "
             "cores' power; needs root, else a warning; -1: the machine's own", "us", -1,
             1_000_000, "-1: off; 0: idle cores poll",
             read_only="the request is made at start; " + START_ONLY),
        Spec("qos_reliability", "reliable", "reliability of every rig topic",
             read_only="publishers and subscriptions are made with it; " + START_ONLY,
             choices=("reliable", "best_effort")),
        Spec("command_owner", "any", "who may command the rig: any (every publisher's "
             "commands are taken; several publishers on one command topic are warned about) "
             "or first (each command topic belongs to the first publisher whose command "
             "arrives, as ros2_control lets one controller claim a command interface: the "
             "others' commands are refused, named in the log and counted on /diagnostics, "
             "until the owner's publisher leaves)",
             read_only="the command subscriptions are made with it; " + START_ONLY,
             choices=("any", "first")),
        Spec("command_timeout_s", 1.0, "command age above which /diagnostics warns", "s",
             0.001, 3600.0),
        Spec("stick_slip_window_s", 4.0 * math.pi * t_star,
             "the stick-slip flag stays up this long after a stick", "s", 0.001, 3600.0),
        Spec("initial_state", "steady", "steady (drilling at the initial commands) or rest "
             "(at rest initial_gap_m above bottom, hanging, not rotating)",
             choices=("steady", "rest")),
        Spec("initial_top_drive_speed_rad_s", preset.top_drive_speed_rad_s,
             "top-drive speed command at start and after reset", "rad/s", 0.0, 40.0, speed),
        Spec("initial_weight_on_bit_n", 1e3 * preset.weight_on_bit_kn,
             "available weight W0 = W_s - H0 at start and after reset", "N", 0.0, 1e6,
             "bits rarely take more than ~450 kN; never more than W_s"),
        Spec("initial_perturbation", 0.0, "with initial_state steady: the bit speed starts "
             "at (1 + this) times the steady speed, so stick-slip can grow from the start "
             "where the steady state is unstable (0: exactly steady; the offline "
             "drill_sim control starts at 1e-3)", "", *PERTURBATION_RANGE,
             "a bit speed between 0.1 and 2 times the steady one"),
        Spec("initial_gap_m", 0.05, "with initial_state rest: bit height above bottom", "m",
             0.0, 30.0, "within a stand (~28 m) of bottom"),
        Spec("max_top_drive_speed_rad_s", 30.0, "top-drive commands above this are refused",
             "rad/s", 0.0, 40.0, speed),
        Spec("max_hook_load_n", 2.0 * rig.submerged_weight_n,
             "hook-load commands above this are refused", "N", 0.0, 1e7,
             "the largest rigs lift ~9 MN (1000 short tons)"),
        Spec("hoist_speed_limit_m_s", 0.5, "the string rises no faster than this", "m/s",
             1e-3, 3.0, "drawworks hoist at up to ~2 m/s"),
        Spec("hook_mode", "force", "the string's axial top boundary: force (the hook holds the "
             "commanded hook load) or position (the drawworks moves the block at "
             "block_speed_m_s and the hook load is measured: ~/joint_states' hook effort; "
             "hook-load commands are then kept but not applied; back to force, the hook holds "
             "the load measured then); position needs string_model distributed",
             choices=("force", "position")),
        Spec("block_speed_m_s", 0.0, "with hook_mode position: the block's speed, positive "
             "down (0: held, a drill-off test)", "m/s", -3.0, 3.0,
             "drawworks move the block at up to ~2-3 m/s"),
        Spec("diagnostics_period_s", 1.0, "period of /diagnostics", "s", 0.05, 60.0,
             read_only="its timer is made at start; " + START_ONLY),
        Spec("record", "", "a new bag directory, in an existing folder, to record the session "
             "into (rosbag2, MCAP); empty: no recording",
             read_only="the bag is opened at start; " + START_ONLY),
        Spec("record_split_duration_s", 0.0, "start a new bag file after this long; 0: never",
             "s", 0.0, 1e7, "a file a second at least: opening and finishing files costs "
             "milliseconds", off_or_at_least=1.0),
        Spec("record_split_size_bytes", 0, "start a new bag file past this size; 0: never",
             "bytes", 0, 2**62, "1 MiB at least: smaller than a chunk, files would split at "
             "every flush", off_or_at_least=MIB),
        Spec("sensor_profile", "ideal", "what the ~/measured/ topics show: a sensor profile "
             "name (ideal, surface_rig, mud_pulse, wired_pipe) or a profile YAML file "
             "(msg_docs/sensors.md)",
             read_only="the sensors' filters and delays start with the session (bag resim "
                       "re-runs them); " + START_ONLY),
        Spec("sensor_seed", 0, "seed of the sensors' noise: the same seed, the same noise",
             "", 0, MAX_SENSOR_SEED, "a non-negative 32-bit whole number",
             read_only="the noise streams start from it; " + START_ONLY),
        Spec("measured_publish", "every_tick", "when each ~/measured/ topic is published: "
             "every_tick (the held value, every tick) or on_sample (only in the ticks where one "
             "of its channels takes a fresh value: at the sensor's own rate, a mud-pulse word "
             "when it arrives); recorded the same",
             choices=("every_tick", "on_sample")),
    ]
    return out + top_drive_specs(preset)


def top_drive_specs(preset: Preset) -> list[Spec]:
    """The top drive's parameters (``core.top_drive.TopDriveParameters``' fields, defaults
    from the preset); all change at run time, a change of mode bumplessly."""
    d = preset.top_drive
    rate = 0.0 if d.motor_torque_rate_nm_s == math.inf else d.motor_torque_rate_nm_s
    torque = "top drives deliver ~30-110 kN m; 1 MN m is beyond any"
    return [
        Spec("top_drive_mode", d.top_drive_mode, "kinematic (an ideal speed source), speed "
             "(the drive's own PI on the speed set-point) or torque (the motor torque is the "
             "command ~/cmd/top_drive_torque)", choices=TOP_DRIVE_MODES),
        Spec("top_drive_inertia_kg_m2", d.top_drive_inertia_kg_m2, "top drive's polar inertia "
             "J_TD (motor, gearbox, quill)", "kg m^2", 1.0, 1e5,
             "published field models use ~2900 kg m^2; 1e5 is close to an ideal speed source"),
        Spec("motor_torque_max_nm", d.motor_torque_max_nm, "largest motor torque T_max", "N m",
             0.0, 1e6, torque),
        Spec("motor_torque_min_nm", d.motor_torque_min_nm, "smallest motor torque T_min (0: a "
             "drive that cannot brake)", "N m", -1e6, 0.0, torque),
        Spec("motor_torque_rate_nm_s", rate, "motor torque rate limit; 0: none", "N m/s",
             0.0, 1e9, "drives ramp their torque in ~10 ms to seconds", off_or_at_least=1.0),
        Spec("drive_lag_s", d.drive_lag_s, "time constant of the motor torque's first-order "
             "lag (the drive's current loop); 0: none", "s", 0.0, 10.0,
             "current loops settle in ~1-50 ms"),
        Spec("drive_kp_nm_s_rad", float(d.drive_kp_nm_s_rad or 0.0), "speed mode: the drive "
             "PI's proportional gain K_p (default 50 Z, Z the pipe's torsional impedance)",
             "N m s/rad", 0.0, 1e8, "a stiff PI is ~50 Z (1.5e4 on base)"),
        Spec("drive_ki_nm_rad", float(d.drive_ki_nm_rad), "speed mode: the drive PI's "
             "integral gain K_i (default 5 J_TD [1/s^2])", "N m/rad", 0.0, 1e9,
             "5 J_TD is 1.45e4 for 2900 kg m^2"),
    ]


PRESET_READ_ONLY = "the preset sets every model parameter's default; " + START_ONLY
SPLITS = ("record_split_duration_s", "record_split_size_bytes")


def cross_refusal(values: dict[str, object]) -> str | None:
    """Why a set of values does not hold together, or None."""
    if values["max_speed"] and not values["publish_clock"]:
        return ("max_speed = true needs publish_clock = true: faster than real time, a "
                "controller can only follow the simulation on /clock")
    if values["lockstep"] and not values["publish_clock"]:
        return ("lockstep = true needs publish_clock = true: the commands answer ticks by "
                "their /clock time")
    if values["initial_weight_on_bit_n"] > values["submerged_weight_n"]:
        return (f"initial_weight_on_bit_n = {values['initial_weight_on_bit_n']:g} N exceeds "
                f"submerged_weight_n = {values['submerged_weight_n']:g} N: the string cannot "
                "put more than its own weight on the bit")
    return None


def checked_change(by_name: dict[str, Spec], old: dict[str, object],
                   changes: dict[str, object]) -> dict[str, object]:
    """The parameters ``old`` with ``changes`` made, checked against the table: each a
    parameter that may change at run time, in its type and range, and the cross-checks hold.
    Raises ParameterError naming the first that is not, with what is expected."""
    import difflib

    from ..core.parameters import ParameterError
    new = dict(old)
    for name, value in changes.items():
        spec = by_name.get(name)
        if spec is None:
            near = difflib.get_close_matches(name, list(by_name), n=1)
            raise ParameterError(f"{name}: no such parameter" + (
                f"; did you mean {near[0]}?" if near else "; expected a parameter of the "
                "node (msg_docs/node.md)"))
        if spec.read_only:
            raise ParameterError(f"{name} cannot change at run time: {spec.read_only}")
        new[name], refusal = spec.check(value)
        if refusal is not None:
            raise ParameterError(refusal)
    if (refusal := cross_refusal(new)) is not None:
        raise ParameterError(refusal)
    return new
