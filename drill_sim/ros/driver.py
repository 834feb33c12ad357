"""The node behind ``drill_sim_drive`` (its command line: ``drill_sim.cli.drive``): plays a
driller scenario onto the rig's command topics, or holds one speed and weight on bit.

It reads the string's submerged weight from the rig node (to turn WOB set points into hook
loads), waits until the rig subscribes to both command topics, then publishes the set points at
``--rate-hz`` on the node's clock (so it follows ``/clock`` with ``use_sim_time:=true``). A
scenario with a ``controller`` section switches that controller node (``--controller``, a
``drill_sim_controller``) on at its time by setting its ``enabled`` parameter.
"""

from __future__ import annotations

import rclpy
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rcl_interfaces.srv import GetParameters, SetParameters
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

from ..session.scenario import FOREVER_S, Scenario
from ..wire import rig_topics
from .controller_switch import switch_on_request
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
        self.controller_client.call_async(switch_on_request(law))
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


def drive(scenario: Scenario, argv: list[str], *, rig: str, rate_hz: float, loop: bool,
          reliability: str, controller: str) -> int:
    """Play ``scenario`` onto the rig ``rig`` until it ends (or Ctrl-C); ``argv`` carries the
    ROS arguments."""
    node = None
    try:                          # a Ctrl-C at any moment, while the node is made too: quietly
        rclpy.init(args=argv)
        node = ScenarioDriver(scenario, rig=rig, rate_hz=rate_hz, loop=loop,
                              reliability=reliability, controller=controller)
        while rclpy.ok() and not node.done:
            rclpy.spin_once(node, timeout_sec=0.1)
        node.get_logger().info("scenario finished")
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0
