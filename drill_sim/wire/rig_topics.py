"""The rig node's topics and services: one table, the source of truth for the node, the driver,
the monitor, the in-node recorder, the bag tools and msg_docs/node.md.

Each entry gives the name (node-relative ``~/...`` so ``-r __ns:=/rig1`` namespaces a whole rig,
or absolute), the ROS type, the direction, the QoS, and for outputs which ``RigSample`` field
fills which message field, with its SI unit. The node creates its publishers, subscriptions and
services by walking the table, and its outputs' encoders are compiled from it (``rig_messages``),
so adding an output is one entry here plus its line in msg_docs/node.md. Which field of a
command carries it, and the limit that applies, are the session's rules: ``command`` names the
rule in ``session.rules.COMMANDS``.

Outputs are published every tick in table order (``/clock`` first when published). Most carry
the model's exact state (for evaluation and plots); those under ``~/measured/`` carry what the
rig's sensors show (``core.sensors``, the ``sensor_profile`` parameter), the signals a controller
under test reads: their fields name ``Measured`` fields (``source`` MEASURED).
"""

from __future__ import annotations

from dataclasses import dataclass

from . import WireError
from .qos import Qos

NODE_NAME = "drill_sim"
# frames: "bit": +z downhole at the bit; "top_drive": at the surface, same orientation
FRAME_BIT, FRAME_TOP_DRIVE = "bit", "top_drive"
JOINT_NAMES = ("top_drive", "hook", "bit_rotation", "bit_axial")

# directions
OUTPUT = "output"              # published every tick
COMMAND = "command"            # subscribed; held until the next tick
SERVICE = "service"
DIAGNOSTICS = "diagnostics"    # published every diagnostics_period_s
CLOCK = "clock"                # published every tick with publish_clock:=true
EVENTS = "events"              # recorded only (resets, parameter changes), never published

RIG_QOS = Qos()                # KEEP_LAST 10; reliability from the qos_reliability parameter

# what fills an output's fields: the exact RigSample, or the sensors' Measured
SAMPLE, MEASURED = "sample", "measured"


@dataclass(frozen=True)
class Field:
    """One message field (its path, e.g. ``wrench.force.z``, ``position[1]``, ``data``) filled
    from the ``RigSample`` field ``sample``, in ``unit`` ("" for flags and codes)."""

    message: str
    sample: str
    unit: str


@dataclass(frozen=True)
class RigTopic:
    """One topic or service of the rig node, as the node offers it."""

    name: str                          # "~/bit/wrench" (node-relative) or "/clock"
    type_name: str                     # pkg/msg/Type or pkg/srv/Type
    direction: str
    qos: Qos | None = RIG_QOS          # None for services
    fixed_qos: bool = False            # True: qos_reliability does not change this one
    fields: tuple[Field, ...] = ()     # outputs: what fills the message; stamps are implicit
    frame_id: str = ""                 # header.frame_id of outputs
    joints: tuple[str, ...] = ()       # JointState names
    command: str = ""                  # commands: the rule in session.rules.COMMANDS
    source: str = SAMPLE               # outputs: SAMPLE (exact state) or MEASURED (sensors)

    def under(self, node: str) -> str:
        """The name for the rig node ``node`` (``/rig1/drill_sim``, or relative ``drill_sim``)."""
        return node + self.name[1:] if self.name.startswith("~/") else self.name

    def qos_for(self, reliability: str) -> Qos:
        """The QoS this topic is offered with when the node's qos_reliability is ``reliability``."""
        if self.qos is None:
            raise WireError(f"{self.name} is a service: no QoS")
        return self.qos if self.fixed_qos else self.qos.with_reliability(reliability)


def _joints(array: str, *sample_units: tuple[str, str]) -> tuple[Field, ...]:
    """``array[j]`` of JointState from (sample, unit) for each joint of JOINT_NAMES."""
    return tuple(Field(f"{array}[{j}]", s, u) for j, (s, u) in enumerate(sample_units))


TOPICS: tuple[RigTopic, ...] = (
    RigTopic("/clock", "rosgraph_msgs/msg/Clock", CLOCK, fixed_qos=True),
    RigTopic("~/bit/wrench", "geometry_msgs/msg/WrenchStamped", OUTPUT, frame_id=FRAME_BIT,
             fields=(Field("wrench.force.z", "wob_n", "N"),
                     Field("wrench.torque.z", "tob_nm", "N m"))),
    RigTopic("~/bit/twist", "geometry_msgs/msg/TwistStamped", OUTPUT, frame_id=FRAME_BIT,
             fields=(Field("twist.linear.z", "rop_m_s", "m/s"),
                     Field("twist.angular.z", "bit_speed_rad_s", "rad/s"))),
    RigTopic("~/bit/stick_slip", "std_msgs/msg/Bool", OUTPUT,
             fields=(Field("data", "stick_slip", ""),)),
    RigTopic("~/top_drive/wrench", "geometry_msgs/msg/WrenchStamped", OUTPUT,
             frame_id=FRAME_TOP_DRIVE,
             fields=(Field("wrench.force.z", "hook_load_n", "N"),
                     Field("wrench.torque.z", "surface_torque_nm", "N m"))),
    RigTopic("~/bit/depth_of_cut", "std_msgs/msg/Float64", OUTPUT,
             fields=(Field("data", "depth_of_cut_m", "m"),)),
    RigTopic("~/bit/hole_depth", "std_msgs/msg/Float64", OUTPUT,
             fields=(Field("data", "hole_depth_m", "m"),)),
    RigTopic("~/joint_states", "sensor_msgs/msg/JointState", OUTPUT, joints=JOINT_NAMES,
             fields=_joints("position", ("top_drive_angle_rad", "rad"), ("bit_depth_m", "m"),
                            ("bit_angle_rad", "rad"), ("hole_depth_m", "m"))
             + _joints("velocity", ("top_drive_speed_rad_s", "rad/s"), ("rop_m_s", "m/s"),
                       ("bit_speed_rad_s", "rad/s"), ("rop_m_s", "m/s"))
             + _joints("effort", ("surface_torque_nm", "N m"), ("hook_load_n", "N"),
                       ("tob_nm", "N m"), ("wob_n", "N"))),
    RigTopic("~/bit/regime", "std_msgs/msg/UInt8", OUTPUT, fields=(Field("data", "regime", ""),)),
    RigTopic("~/top_drive/twist", "geometry_msgs/msg/TwistStamped", OUTPUT,
             frame_id=FRAME_TOP_DRIVE,
             fields=(Field("twist.angular.z", "top_drive_speed_rad_s", "rad/s"),)),
    RigTopic("~/top_drive/motor_wrench", "geometry_msgs/msg/WrenchStamped", OUTPUT,
             frame_id=FRAME_TOP_DRIVE,
             fields=(Field("wrench.torque.z", "motor_torque_nm", "N m"),)),
    # what the rig's sensors show (sensor_profile), held between fresh samples
    RigTopic("~/measured/top_drive/wrench", "geometry_msgs/msg/WrenchStamped", OUTPUT,
             frame_id=FRAME_TOP_DRIVE, source=MEASURED,
             fields=(Field("wrench.force.z", "hook_load_n", "N"),
                     Field("wrench.torque.z", "surface_torque_nm", "N m"))),
    RigTopic("~/measured/top_drive/twist", "geometry_msgs/msg/TwistStamped", OUTPUT,
             frame_id=FRAME_TOP_DRIVE, source=MEASURED,
             fields=(Field("twist.angular.z", "top_drive_speed_rad_s", "rad/s"),)),
    RigTopic("~/measured/top_drive/motor_wrench", "geometry_msgs/msg/WrenchStamped", OUTPUT,
             frame_id=FRAME_TOP_DRIVE, source=MEASURED,
             fields=(Field("wrench.torque.z", "motor_torque_nm", "N m"),)),
    RigTopic("~/measured/bit/wrench", "geometry_msgs/msg/WrenchStamped", OUTPUT,
             frame_id=FRAME_BIT, source=MEASURED,
             fields=(Field("wrench.force.z", "wob_n", "N"),
                     Field("wrench.torque.z", "tob_nm", "N m"))),
    RigTopic("~/measured/bit/twist", "geometry_msgs/msg/TwistStamped", OUTPUT,
             frame_id=FRAME_BIT, source=MEASURED,
             fields=(Field("twist.angular.z", "bit_speed_rad_s", "rad/s"),)),
    RigTopic("~/measured/bit/stick_slip_severity", "std_msgs/msg/Float64", OUTPUT,
             source=MEASURED, fields=(Field("data", "stick_slip_severity", ""),)),
    RigTopic("~/cmd/top_drive", "geometry_msgs/msg/TwistStamped", COMMAND, command="top_drive"),
    RigTopic("~/cmd/hook_load", "geometry_msgs/msg/WrenchStamped", COMMAND, command="hook_load"),
    RigTopic("~/cmd/top_drive_torque", "geometry_msgs/msg/WrenchStamped", COMMAND,
             command="top_drive_torque"),
    RigTopic("~/cmd/joint_commands", "sensor_msgs/msg/JointState", COMMAND,
             command="joint_commands"),
    RigTopic("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray", DIAGNOSTICS, fixed_qos=True),
    RigTopic("~/events", "std_msgs/msg/String", EVENTS),
    RigTopic("~/reset", "std_srvs/srv/Trigger", SERVICE, None),
    RigTopic("~/pause", "std_srvs/srv/SetBool", SERVICE, None),
    RigTopic("~/step", "std_srvs/srv/Trigger", SERVICE, None),
)


def topic(name: str) -> RigTopic:
    """The table's entry named ``name``."""
    for t in TOPICS:
        if t.name == name:
            return t
    raise KeyError(f"{name} is not one of the rig's topics")


def of(direction: str) -> tuple[RigTopic, ...]:
    """The table's entries of one direction, in table order."""
    return tuple(t for t in TOPICS if t.direction == direction)


CLOCK_TOPIC = topic("/clock")
JOINT_STATES = topic("~/joint_states")
BIT_STICK_SLIP = topic("~/bit/stick_slip")
DIAGNOSTICS_TOPIC = topic("/diagnostics")
EVENTS_TOPIC = topic("~/events")
OUTPUTS = of(OUTPUT)
MEASURED_OUTPUTS = tuple(t for t in OUTPUTS if t.source == MEASURED)
COMMANDS = of(COMMAND)
SERVICES = of(SERVICE)
COMMAND_BY_RULE = {t.command: t for t in COMMANDS}


def _joint_places() -> dict[str, tuple[str, int]]:
    """Where each quantity sits in ``~/joint_states``: (array, joint index), read from the
    table's fields; the ROP, shown on two joints, at the bit's axial joint (the last)."""
    places = {}
    for f in JOINT_STATES.fields:
        array, j = f.message.rstrip("]").split("[")
        places[f.sample] = (array, int(j))
    return places


JOINT_PLACES = _joint_places()


def published(with_clock: bool) -> tuple[RigTopic, ...]:
    """What the node publishes every tick, in publishing order (``/clock`` first)."""
    return ((CLOCK_TOPIC,) if with_clock else ()) + OUTPUTS


def recorded(with_clock: bool) -> tuple[RigTopic, ...]:
    """What the in-node recorder writes, in the order its channels are declared."""
    return published(with_clock) + COMMANDS + (EVENTS_TOPIC, DIAGNOSTICS_TOPIC)
