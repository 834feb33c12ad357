"""``drill_sim_drive``: plays a driller scenario onto the rig's command topics, or holds one
speed and weight on bit (``drill_sim_drive hold --rpm 60 --wob-kn 100``).

It reads the string's submerged weight from the rig node (to turn WOB set points into hook
loads), waits until the rig subscribes to both command topics, then publishes the set points at
``--rate-hz`` on the node's clock (so it follows ``/clock`` with ``use_sim_time:=true``). A
scenario with a ``controller`` section switches that controller node (``--controller``, a
``drill_sim_controller``) on at its time by setting its ``enabled`` parameter.
"""

from __future__ import annotations

import argparse
import sys

import rclpy
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.msg import ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameters, SetParameters
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.utilities import remove_ros_args

from ..core import ParameterError
from ..core.scenario import Scenario, load_scenario, scenario_from_dict, scenario_names
from ..wire import rig_topics
from ..wire.qos import RELIABILITIES
from .topics import rclpy_qos

SPEED, HOOK = rig_topics.COMMAND_BY_RULE["top_drive"], rig_topics.COMMAND_BY_RULE["hook_load"]


class ScenarioDriver(Node):
    def __init__(self, scenario: Scenario, *, rig: str, rate_hz: float, loop: bool,
                 reliability: str = "reliable", controller: str = "drill_sim_controller") -> None:
        super().__init__("drill_sim_drive")
        self.scenario, self.loop = scenario, loop
        self.pub_speed = self.create_publisher(TwistStamped, SPEED.under(rig),
                                               rclpy_qos(SPEED.qos_for(reliability)))
        self.pub_hook = self.create_publisher(WrenchStamped, HOOK.under(rig),
                                              rclpy_qos(HOOK.qos_for(reliability)))
        self.params_client = self.create_client(GetParameters, f"{rig}/get_parameters")
        self.submerged_weight_n: float | None = None
        self.t0_ns: int | None = None
        self.done = False
        self.speed_msg, self.hook_msg = TwistStamped(), WrenchStamped()
        self.speed_msg.header.frame_id = self.hook_msg.header.frame_id = rig_topics.FRAME_TOP_DRIVE
        self.create_timer(1.0 / rate_hz, self._tick)
        self._pending = None
        self.controller_client = None if scenario.controller is None else self.create_client(
            SetParameters, f"{controller}/set_parameters")
        self.controller_on = False

    def _tick(self) -> None:
        if self.submerged_weight_n is None:
            self._ask_weight()
            return
        if self.t0_ns is None:
            if self.pub_speed.get_subscription_count() and self.pub_hook.get_subscription_count():
                self.t0_ns = self.get_clock().now().nanoseconds
                sc = self.scenario
                self.get_logger().info(f"playing scenario '{sc.name}' ({sc.description}; " + (
                    "until stopped)" if sc.duration_s >= FOREVER_S else f"{sc.duration_s:g} s)"))
            return
        now = self.get_clock().now()
        t = (now.nanoseconds - self.t0_ns) * 1e-9
        if t > self.scenario.duration_s:
            if not self.loop:
                self.done = True
                return
            self.t0_ns = now.nanoseconds
            t = 0.0
        switch = self.scenario.controller
        if switch is not None and not self.controller_on and t >= switch.on_at_s:
            self._switch_on(switch.law, t)
        speed, hook = self.scenario.commands_at(t, self.submerged_weight_n)
        stamp = now.to_msg()
        self.speed_msg.header.stamp = self.hook_msg.header.stamp = stamp
        self.speed_msg.twist.angular.z = speed
        self.hook_msg.wrench.force.z = hook
        self.pub_speed.publish(self.speed_msg)
        self.pub_hook.publish(self.hook_msg)

    def _switch_on(self, law: str, t: float) -> None:
        """Set the controller's law and ``enabled`` (once its parameter service is there)."""
        if not self.controller_client.service_is_ready():
            return
        self.controller_on = True
        value = ParameterValue
        self.controller_client.call_async(SetParameters.Request(parameters=[
            ParameterMsg(name="law", value=value(type=ParameterType.PARAMETER_STRING,
                                                 string_value=law)),
            ParameterMsg(name="enabled", value=value(type=ParameterType.PARAMETER_BOOL,
                                                     bool_value=True))]))
        self.get_logger().info(f"controller {law} switched on at t = {t:.2f} s")

    def _ask_weight(self) -> None:
        if self._pending is None:
            if not self.params_client.service_is_ready():
                return
            self._pending = self.params_client.call_async(
                GetParameters.Request(names=["submerged_weight_n"]))
        elif self._pending.done():
            values = self._pending.result().values
            self.submerged_weight_n = float(values[0].double_value)
            self._pending = None


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


def _scenario(args: argparse.Namespace) -> Scenario:
    """The scenario the arguments name (ParameterError or ValueError if they do not hold)."""
    given = [f"--{k.replace('_', '-')}" for k in ("rpm", "wob_kn", "hook_load_kn", "duration")
             if getattr(args, k) is not None]
    if args.scenario != HOLD:
        if given:
            raise ValueError(f"{', '.join(given)}: only with the hold scenario "
                             "(drill_sim_drive hold --rpm 60 --wob-kn 100)")
        return load_scenario(args.scenario)
    if args.rpm is None or (args.wob_kn is None) == (args.hook_load_kn is None):
        raise ValueError("hold needs --rpm and one of --wob-kn or --hook-load-kn")
    return hold_scenario(args.rpm, args.wob_kn, args.hook_load_kn, args.duration)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv if argv is None else argv
    parser = argparse.ArgumentParser(prog="drill_sim_drive", description=__doc__.split("\n")[0])
    parser.add_argument("scenario", nargs="?", default="tag_bottom",
                        help=f"shipped ({', '.join(scenario_names())}), a scenario YAML file, "
                             "or hold (with --rpm and --wob-kn or --hook-load-kn)")
    parser.add_argument("--rig", default=rig_topics.NODE_NAME, help="name of the rig node")
    parser.add_argument("--rate-hz", type=float, default=50.0, help="command rate [Hz]")
    parser.add_argument("--loop", action="store_true", help="repeat the scenario")
    parser.add_argument("--qos-reliability", choices=RELIABILITIES, default=RELIABILITIES[0])
    parser.add_argument("--controller", default="drill_sim_controller",
                        help="the controller node a scenario's controller section switches on")
    hold = parser.add_argument_group("hold: a constant speed and weight")
    hold.add_argument("--rpm", type=float, help="top-drive speed [rpm]")
    hold.add_argument("--wob-kn", type=float, help="weight on bit W0 = W_s - H0 [kN]")
    hold.add_argument("--hook-load-kn", type=float, help="hook load H0 [kN]")
    hold.add_argument("--duration", type=float, help="seconds to hold (default: until stopped)")
    args = parser.parse_args(remove_ros_args(argv)[1:])
    if not 0 < args.rate_hz <= 1000:
        parser.error(f"--rate-hz = {args.rate_hz:g}: expected 0 < rate <= 1000")
    try:
        scenario = _scenario(args)
    except (ParameterError, ValueError) as exc:
        parser.error(str(exc))
    rclpy.init(args=argv)
    node = ScenarioDriver(scenario, rig=args.rig, rate_hz=args.rate_hz, loop=args.loop,
                          reliability=args.qos_reliability, controller=args.controller)
    try:
        while rclpy.ok() and not node.done:
            rclpy.spin_once(node, timeout_sec=0.1)
        node.get_logger().info("scenario finished")
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
