"""``drill_sim_controller``: a reference stick-slip controller closed around the rig node through
the rig's documented topics only, as a user's controller would be (msg_docs/controller.md).

Every rig tick it takes the top-drive speed, the motor torque applied and the surface torque
(``~/measured/...`` by default, the exact ``~/top_drive/...`` with ``inputs:=exact``), steps
the law once those three readings of the same stamp are in, and publishes the motor torque on
the rig's ``~/cmd/top_drive_torque`` stamped with that sample's stamp (what the rig's lockstep
mode waits for). The set-point is the speed on ``setpoint_topic`` (default the rig's own
``~/cmd/top_drive``, so a driller's speed commands steer it); with ``setpoint_lockstep`` each
sample also waits for a set-point stamped with its stamp and applies it before the law's step,
so a changing set-point meets the samples in a defined order (a scenario player in lockstep
with the rig, e.g. ``drill_sim control --ros``). Law, gains and ``enabled`` change
at run time, validated, without a bump; ``/diagnostics`` reports law, saturation and wind-up.
"""

from __future__ import annotations

import json
import math
import sys
import time

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.msg import (
    ParameterDescriptor,
    ParameterType,
    ParameterValue,
    SetParametersResult,
)
from rcl_interfaces.srv import GetParameters, SetParameters
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter

from ..control import LAWS
from ..control.policy import POLICY_LAW, PolicyLaw, load_policy
from ..control.sampled_loop import MOTOR, SETPOINT, SPEED, SURFACE, SampledLoop, controller_status
from ..control.supervisor import Supervisor, law_gain_defaults
from ..control.tuning import pipe_impedance
from ..control.z_torque import ZTorque
from ..core.parameters import ParameterError
from ..wire import rig_topics
from ..wire.qos import RELIABLE
from .parameters import warn_unknown_given
from .stopping import init_stoppable
from .topics import rclpy_qos

NODE_NAME = "drill_sim_controller"
CONTROL_LAWS = tuple(n for n, law in LAWS.items() if law.output_kind == "torque")
SELECTABLE = (*CONTROL_LAWS, POLICY_LAW)     # what ``law`` takes: a torque law or the policy
PROVISIONAL_PERIOD_S = 1e-3               # gains are checked against it until the rig answers
RATE_QUERY_PERIOD_S = 0.1                 # the rig's rate_hz is asked this often until known
HAND_BACK_TIMEOUT_S = 2.0                 # stopping: how long to wait for the rig's speed mode
# (input, measured topic, exact topic): the rig's names, from its table
INPUTS = (("speed", "~/measured/top_drive/twist", "~/top_drive/twist"),
          ("motor", "~/measured/top_drive/motor_wrench", "~/top_drive/motor_wrench"),
          ("surface", "~/measured/top_drive/wrench", "~/top_drive/wrench"))
TORQUE_COMMAND = "~/cmd/top_drive_torque"
SPEED_COMMAND = "~/cmd/top_drive"


def _real(name: str, value: object) -> float:
    """A real parameter's value: a float, or an integer taken as one (as the rig takes them);
    ParameterError naming it otherwise (the range is the law's or the caller's to check)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{name} = {value!r}: expected a number")
    return float(value)


def rig_topic(name: str) -> rig_topics.RigTopic:
    """The rig's table entry ``name``; a rig without it is a start-up error naming it."""
    try:
        return rig_topics.topic(name)
    except KeyError:
        raise SystemExit(f"{NODE_NAME}: the rig offers no {name} in this build: expected the "
                         "top drive's topics (msg_docs/node.md)") from None


# the controller's own parameters (name, default, description); the gains are declared per law
# as LAW.GAIN (``law_gain_defaults``)
PARAMETERS = (
    ("rig", rig_topics.NODE_NAME, "the rig node's name (e.g. /rig1/drill_sim)"),
    ("law", "z_torque", f"one of {', '.join(CONTROL_LAWS)}, or policy (the callable of "
                        "``policy``)"),
    ("policy", "", "package.module:callable, a policy with drill_sim.gym's interface "
                   "(observation -> motor torque [N m]), run when law is policy"),
    ("enabled", True, "false: the law is off; each sample is answered with a hold (the last "
                      "command) unless manage_drive_mode hands the drive back to its speed "
                      "loop; true again: take over bumplessly"),
    ("sample_period_s", 0.0, "the law's h [s]; 0: the rig's 1/rate_hz, read from its "
                             "parameters at start"),
    ("impedance_nm_s_rad", pipe_impedance("base"),
     "the pipe's Z = J_p sqrt(G rho) [N m s/rad]; default the base pipe's"),
    ("top_drive_inertia_kg_m2", 2900.0, "J_TD [kg m^2], as the rig's"),
    ("inputs", "measured", "measured (~/measured/...) or exact (~/top_drive/...)"),
    ("setpoint_topic", "", "TwistStamped speed set-point [rad/s]; '': the rig's "
                           "~/cmd/top_drive"),
    ("initial_speed_setpoint_rad_s", 2.0 * math.pi, "set-point until one arrives"),
    ("setpoint_lockstep", False, "true: each sample waits for a set-point stamped with "
                                 "its stamp and applies it before the step"),
    ("manage_drive_mode", False, "set the rig's top_drive_mode: torque when enabled, "
                                 "speed when disabled"),
    ("diagnostics_period_s", 1.0, "/diagnostics period [s]"),
)


class ControllerNode(Node):
    def __init__(self) -> None:
        super().__init__(NODE_NAME)
        try:
            p = self._declare_all()
        except (InvalidParameterTypeException, InvalidParameterValueException,
                ParameterError) as exc:
            raise SystemExit(f"{NODE_NAME}: {exc}") from None
        if p["law"] not in SELECTABLE:
            raise SystemExit(f"{NODE_NAME}: law = {p['law']!r}: expected one of "
                             f"{', '.join(SELECTABLE)}")
        try:
            self.policy = load_policy(p["policy"]) if p["policy"] else None
        except ParameterError as exc:
            raise SystemExit(f"{NODE_NAME}: {exc}") from None
        if p["law"] == POLICY_LAW and self.policy is None:
            raise SystemExit(f"{NODE_NAME}: law = policy needs policy = package.module:callable "
                             "(e.g. -p policy:=drill_sim.control.policy:proportional_speed_policy)")
        self._hooks: dict[int, float] = {}      # the hook load [N] by stamp, for a policy
        self.rig = p["rig"]
        self._p = p
        warn_unknown_given(self)
        period = p["sample_period_s"]
        if not (isinstance(period, float) and math.isfinite(period) and 0.0 <= period <= 1.0):
            raise SystemExit(f"{NODE_NAME}: sample_period_s = {period!r}: expected 0 (the "
                             "rig's 1/rate_hz, read from it) or a period in seconds up to 1")
        # Until the rig says its rate, the gains are checked against a provisional period and
        # samples wait (the latest complete one is stepped as soon as the period is known).
        self.core = self._supervisor(period or PROVISIONAL_PERIOD_S, p["enabled"],
                                     p["initial_speed_setpoint_rad_s"])
        try:
            self._check_every_law()
        except ParameterError as exc:
            raise SystemExit(f"{NODE_NAME}: {exc}") from None
        self._period_known = period > 0.0
        self._deferred: tuple | None = None
        # what the rig says of itself: in lockstep? its drive's mode (kept up to date by the
        # mode switches this node asks for); None until it has answered
        self._rig_lockstep = False
        self._drive_mode: str | None = None
        self._last_sample: tuple | None = None      # (stamp, motor torque [N m]) of the last
        self._speed_pub = None                      # the rig's speed command, made when needed
        self._rate_client = self.create_client(GetParameters, f"{self.rig}/get_parameters")
        self._rate_future = None
        self._rate_timer = self.create_timer(RATE_QUERY_PERIOD_S, self._ask_rate)
        if not self._period_known:
            self.get_logger().info(f"waiting for {self.rig}'s rate_hz (sample_period_s 0: "
                                   "the law steps once a rig tick)")
        if p["inputs"] not in ("measured", "exact"):
            raise SystemExit(f"{NODE_NAME}: inputs = {p['inputs']!r}: expected measured or exact")
        use = 1 if p["inputs"] == "measured" else 2
        self.loop = SampledLoop(with_setpoint=p["setpoint_lockstep"])
        for i, entry in enumerate(INPUTS):
            t = rig_topic(entry[use])
            msg_type = TwistStamped if entry[0] == "speed" else WrenchStamped
            self.create_subscription(msg_type, t.under(self.rig),
                                     lambda msg, i=i: self._on_input(i, msg),
                                     rclpy_qos(t.qos_for(RELIABLE).with_depth(100)))
        cmd = rig_topic(TORQUE_COMMAND)
        self.pub = self.create_publisher(WrenchStamped, cmd.under(self.rig),
                                         rclpy_qos(cmd.qos_for(RELIABLE)))
        setpoint = p["setpoint_topic"] or rig_topic(SPEED_COMMAND).under(self.rig)
        self.create_subscription(TwistStamped, setpoint, self._on_setpoint,
                                 rclpy_qos(rig_topic(SPEED_COMMAND).qos_for(RELIABLE)))
        self.diag = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self.create_timer(p["diagnostics_period_s"], self._diagnose)
        self.manage_mode = p["manage_drive_mode"]
        self.mode_client = self.create_client(SetParameters, f"{self.rig}/set_parameters")
        self._mode_request = None
        self.create_timer(0.1, self._send_mode)
        self.msg = WrenchStamped()
        self.msg.header.frame_id = rig_topics.FRAME_TOP_DRIVE
        self.add_on_set_parameters_callback(self._on_parameters)
        if self.manage_mode and self.core.enabled:      # on once the rig's drive is in torque
            self.core.set_enabled(False)
            self._request_mode("torque", lambda: self.core.set_enabled(True))

    # ---- parameters ---------------------------------------------------------------------
    def _declare_all(self) -> dict[str, object]:
        d = ParameterDescriptor
        values = {}
        for name, default, text in PARAMETERS:
            real = isinstance(default, float)         # an integer is taken where a real is
            values[name] = self.declare_parameter(
                name, default, d(description=text, dynamic_typing=real, read_only=name in (
                    "rig", "sample_period_s", "inputs", "setpoint_topic", "policy",
                    "setpoint_lockstep", "diagnostics_period_s"))).value
            if real:
                values[name] = _real(name, values[name])
        z, j = values["impedance_nm_s_rad"], values["top_drive_inertia_kg_m2"]
        for law in CONTROL_LAWS:
            for gain, default in law_gain_defaults(law, z, j).items():
                self.declare_parameter(f"{law}.{gain}", default, d(
                    description=f"{law}: {gain} (msg_docs/control.md)", dynamic_typing=True))
        return values

    def _supervisor(self, h_s: float, enabled: bool, speed_set_rad_s: float) -> Supervisor:
        """The law of the current parameters at period ``h_s``; a bad gain ends the node."""
        p = self._p
        law = str(self.get_parameter("law").value)
        try:
            return Supervisor(h_s, p["impedance_nm_s_rad"], p["top_drive_inertia_kg_m2"], law,
                              self._gains(law), enabled=enabled, speed_set_rad_s=speed_set_rad_s,
                              policy=self.policy)
        except ParameterError as exc:
            raise SystemExit(f"{NODE_NAME}: {exc}") from None

    def _ask_rate(self) -> None:
        """Ask the rig its rate_hz, lockstep and top_drive_mode until it answers; then the
        law at h = 1/rate_hz (unless sample_period_s gave h)."""
        if self._rate_future is not None or not self._rate_client.service_is_ready():
            return
        self._rate_future = self._rate_client.call_async(
            GetParameters.Request(names=["rate_hz", "lockstep", "top_drive_mode"]))
        self._rate_future.add_done_callback(self._on_rate)

    def _on_rate(self, future) -> None:
        self._rate_future = None
        result = future.result()
        values = [] if result is None else list(result.values)
        rate = values[0].double_value if values and values[0].type == \
            ParameterType.PARAMETER_DOUBLE else math.nan
        if not (math.isfinite(rate) and rate > 0.0):
            self.get_logger().warning(f"{self.rig} gave no usable rate_hz ({rate!r}); asking "
                                      "again", throttle_duration_sec=5.0)
            return
        self._rate_timer.cancel()
        if len(values) == 3:
            self._rig_lockstep = values[1].type == ParameterType.PARAMETER_BOOL and \
                values[1].bool_value
            if self._drive_mode is None and values[2].type == ParameterType.PARAMETER_STRING:
                self._drive_mode = values[2].string_value
        if self._period_known:
            return
        old = self.core
        self.core = self._supervisor(1.0 / rate, old.enabled, old.speed_set_rad_s)
        self._period_known = True
        self.get_logger().info(f"{self.rig} ticks at {rate:g} Hz: the law's h = "
                               f"{1.0 / rate:g} s")
        if self._deferred is not None:
            stamp, slot = self._deferred
            self._deferred = None
            self._sample(stamp, slot)

    def _gains(self, law: str, changed: dict[str, object] | None = None) -> dict[str, float]:
        """``law``'s gains, the ``changed`` ones new (ParameterError naming one that is not a
        number; an integer is taken as the real it is)."""
        changed = changed or {}
        return {g: _real(f"{law}.{g}", changed.get(f"{law}.{g}",
                                                   self.get_parameter(f"{law}.{g}").value))
                for g in (LAWS[law].GAINS if law in LAWS else ())}

    def _check_every_law(self, changed: dict[str, object] | None = None) -> None:
        """Every law's gains checked, the inactive laws' too (ParameterError naming a bad
        one): a gain is refused when it is set, not when its law is switched on."""
        for law in CONTROL_LAWS:
            self.core.build(law, self._gains(law, changed))

    def _on_parameters(self, params: list[Parameter]) -> SetParametersResult:
        changed = {p.name: p.value for p in params}
        law = str(changed.get("law", self.get_parameter("law").value))
        try:
            for name in ("impedance_nm_s_rad", "top_drive_inertia_kg_m2"):
                if name in changed:
                    raise ParameterError(f"{name} is fixed at start; restart to change it")
            if law not in SELECTABLE:
                raise ParameterError(f"law = {law!r}: expected one of {', '.join(SELECTABLE)}")
            self._check_every_law(changed)
            gains = self._gains(law, changed)
            touches_law = "law" in changed or any(n.startswith(f"{law}.") for n in changed)
            if touches_law:
                self.core.build(law, gains)               # validate before anything changes
        except ParameterError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        if touches_law:
            self.core.replace_law(law, gains)
        if "enabled" in changed:
            enabled = bool(changed["enabled"])
            if not self.manage_mode or enabled == self.core.enabled:
                self.core.set_enabled(enabled)
            elif enabled:                    # on once the rig's drive takes torque commands
                self._request_mode("torque", lambda: self.core.set_enabled(True))
            else:
                self.core.set_enabled(False)
                self._request_mode("speed", None)
            self.get_logger().info(self._enabled_words(enabled))
        return SetParametersResult(successful=True)

    def _enabled_words(self, enabled: bool) -> str:
        """What switching the law on or off does, for the log."""
        if enabled:
            return (f"enabled: {self.core.law.name} takes over bumplessly"
                    + (" once the rig's drive is in torque mode" if self.manage_mode else ""))
        if not self.manage_mode:
            return "disabled: each sample is answered with a hold (the last command)"
        return ("disabled: the rig's drive goes back to its speed loop"
                + ("; each sample is answered with the speed set-point on the rig's "
                   "~/cmd/top_drive (the rig is in lockstep)" if self._rig_lockstep else ""))

    def _request_mode(self, mode: str, then) -> None:
        """Ask the rig to put its drive in ``mode`` (bumpless at the rig) as soon as its
        parameter service is there; ``then()`` once it has. In lockstep the last sample is
        then answered again in the new mode: the rig moved its wait to that mode's command
        topic when it switched, and may be waiting there for this sample's answer."""
        def switched() -> None:
            self._drive_mode = mode
            if then is not None:
                then()
            if self._rig_lockstep and self._last_sample is not None:
                stamp, motor_nm = self._last_sample
                if self.core.enabled:            # the law takes over from the drive's torque
                    self._publish(stamp, motor_nm)
                else:
                    self._answer_disabled(stamp, motor_nm)
        self._mode_request = (mode, switched)
        self._send_mode()

    def _send_mode(self) -> None:
        if self._mode_request is None or not self.mode_client.service_is_ready():
            return
        mode, then = self._mode_request
        self._mode_request = None
        value = ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=mode)
        future = self.mode_client.call_async(SetParameters.Request(
            parameters=[ParameterMsg(name="top_drive_mode", value=value)]))

        def done(f) -> None:
            result = f.result()
            if result is None or not result.results or not result.results[0].successful:
                reason = "no answer" if result is None or not result.results \
                    else result.results[0].reason
                self.get_logger().error(f"the rig refused top_drive_mode = {mode}: {reason}")
            elif then is not None:
                then()
        future.add_done_callback(done)

    def hand_back(self, executor, timeout_s: float = HAND_BACK_TIMEOUT_S) -> None:
        """Stopping while in charge of the drive (``manage_drive_mode``, enabled): put the rig's
        top drive back on its own speed loop (bumpless at the rig) before leaving, so that it
        does not go on applying the last torque command with nobody closing the loop. Waits
        for the rig's answer at most ``timeout_s``; says so if there is none."""
        if not (self.manage_mode and self.core.enabled):
            return
        done: list[bool] = []
        self.core.set_enabled(False)
        self._request_mode("speed", lambda: done.append(True))
        end = time.monotonic() + timeout_s
        while not done and time.monotonic() < end:
            self._send_mode()
            executor.spin_once(timeout_sec=0.05)
        if done:
            self.get_logger().info(f"stopping: {self.rig}'s top drive is back on its speed loop")
        elif self.pub.get_subscription_count() == 0 and not self.mode_client.service_is_ready():
            self.get_logger().info(f"stopping: {self.rig} has stopped too; no drive to hand back")
        else:
            self.get_logger().error(f"stopping: {self.rig} did not take top_drive_mode = speed "
                                    f"within {timeout_s:g} s; its drive holds the last torque "
                                    "command")

    # ---- the loop -----------------------------------------------------------------------
    def _on_setpoint(self, msg: TwistStamped) -> None:
        speed = msg.twist.angular.z
        if self.loop.size == 4:               # applied at the sample with its stamp
            self._on_input(SETPOINT, msg)
        elif math.isfinite(speed):
            self.core.set_speed(speed)
        else:
            self.get_logger().warn(f"set-point {speed!r} rad/s ignored: expected a finite speed")

    def _on_input(self, i: int, msg) -> None:
        stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        value = msg.twist.angular.z if i in (SPEED, SETPOINT) else msg.wrench.torque.z
        if i == SURFACE:                       # the same message's hook load, for a policy
            self._hooks[stamp] = msg.wrench.force.z
            if len(self._hooks) > 64:
                self._hooks.pop(next(iter(self._hooks)))
        slot = self.loop.put(stamp, i, value)
        if slot is None:
            return
        if not self._period_known:            # kept until the rig says its rate
            self._deferred = (msg.header.stamp, slot)
            return
        self._sample(msg.header.stamp, slot)

    def _sample(self, stamp_msg, slot: list) -> None:
        """One complete sample: step the law, publish its command stamped with the sample's."""
        stamp = stamp_msg.sec * 1_000_000_000 + stamp_msg.nanosec
        law = self.core.law
        if isinstance(law, PolicyLaw):
            law.hook_load_n = self._hooks.get(stamp, math.nan)
            refused = law.refused
        out, skipped = self.loop.step(self.core, stamp, slot)
        if isinstance(law, PolicyLaw) and law.refused > refused:
            self.get_logger().warn(f"policy: {law.last_problem}; holding the last command",
                                   throttle_duration_sec=1.0)
        if skipped:
            self.get_logger().warn(skipped)
        elif out is None and not self.core.enabled:
            if not self.manage_mode:
                out = self._hold(slot[MOTOR])
            elif self._rig_lockstep:
                self._answer_disabled(stamp_msg, slot[MOTOR])
        self._last_sample = (stamp_msg, slot[MOTOR])
        if out is not None:
            self._publish(stamp_msg, out)

    def _hold(self, motor_nm: float) -> float:
        """Disabled, the drive taking torque commands: a hold, the last command (else the
        torque the drive applies), so a rig in lockstep goes on as one in real time does,
        where the drive keeps its last command."""
        last = self.core.last_output
        return last if last is not None else motor_nm

    def _answer_disabled(self, stamp, motor_nm: float) -> None:
        """Disabled with manage_drive_mode, the rig in lockstep: answer the sample in the
        drive's mode, so the rig goes on as in real time. Back on its speed loop: the speed
        set-point this node was handed, on the rig's ~/cmd/top_drive (the drive's own
        command then); still in torque mode (the switch not yet made): a hold."""
        if self._drive_mode == "torque":
            self._publish(stamp, self._hold(motor_nm))
            return
        if self._speed_pub is None:
            cmd = rig_topic(SPEED_COMMAND)
            self._speed_pub = self.create_publisher(TwistStamped, cmd.under(self.rig),
                                                    rclpy_qos(cmd.qos_for(RELIABLE)))
            self._speed_msg = TwistStamped()
            self._speed_msg.header.frame_id = rig_topics.FRAME_TOP_DRIVE
        self._speed_msg.header.stamp = stamp
        self._speed_msg.twist.angular.z = self.core.speed_set_rad_s
        self._speed_pub.publish(self._speed_msg)

    def _publish(self, stamp, torque_nm: float) -> None:
        self.msg.header.stamp = stamp
        self.msg.wrench.torque.z = torque_nm
        self.pub.publish(self.msg)

    def _diagnose(self) -> None:
        w = self.core.take_window()
        warn, text = controller_status(self.core, w, self._period_known, self.rig)
        level = DiagnosticStatus.WARN if warn else DiagnosticStatus.OK
        law = self.core.law
        values = {"law": law.name, "enabled": str(self.core.enabled),
                  "sample_period_s": f"{self.core.h_s:.9g}" if self._period_known else "",
                  "samples": str(w["samples"]),
                  "saturation_fraction": f"{w['saturation_fraction']:.4f}",
                  "windup_fraction": f"{w['windup_fraction']:.4f}",
                  "speed_setpoint_rad_s": f"{self.core.speed_set_rad_s:.6g}",
                  "output_nm": "" if self.core.last_output is None
                  else f"{self.core.last_output:.6g}",
                  # what ran: the active law's gains (SI, names as the parameters'), or the
                  # policy's callable
                  "gains": json.dumps(self._gains(law.name)) if law.name in LAWS else "{}",
                  "policy": self._p["policy"] if law.name == POLICY_LAW else "",
                  # Z-Torque's α after its saturation regulator (α itself while it is off)
                  "alpha_in_use": f"{law.alpha_in_use:.6g}" if isinstance(law, ZTorque) else ""}
        arr = DiagnosticArray()
        arr.header.stamp = self.get_clock().now().to_msg()
        arr.status = [DiagnosticStatus(level=level, name=f"{self.get_name()}: controller",
                                       message=f"{law.name}: {text}", hardware_id="drill_sim",
                                       values=[KeyValue(key=k, value=v)
                                               for k, v in values.items()])]
        self.diag.publish(arr)


def main(args: list[str] | None = None) -> int:
    stop = init_stoppable(args, ros_args_only=True)
    node = executor = None
    try:
        node = ControllerNode()
        executor = EventsExecutor()
        executor.add_node(node)
        while not stop:
            executor.spin_once(timeout_sec=0.1)
        node.hand_back(executor)
    except SystemExit as exc:
        print(exc, file=sys.stderr)
        return 2
    except ExternalShutdownException:
        pass
    finally:
        if executor is not None:
            executor.shutdown()
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
