"""Switching a reference controller on from another node: its ``law`` and ``enabled``
parameters set through its parameter service, as a scenario's ``controller`` section asks
(``drill_sim_drive`` playing a scenario, or the rig node playing one itself)."""

from __future__ import annotations

from collections.abc import Callable

from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import SetParameters
from rclpy.node import Node
from rclpy.task import Future


def switch_on_request(law: str) -> SetParameters.Request:
    """The request that sets a controller's ``law`` and enables it."""
    return SetParameters.Request(parameters=[
        Parameter(name="law", value=ParameterValue(type=ParameterType.PARAMETER_STRING,
                                                   string_value=law)),
        Parameter(name="enabled", value=ParameterValue(type=ParameterType.PARAMETER_BOOL,
                                                       bool_value=True))])


def switcher(node: Node, controller: str) -> Callable[[str], Future | None]:
    """``switch(law)`` for ``node``: asks the controller node ``controller`` (relative names
    in the node's namespace) to run ``law``; the call's future, or None (a warning the first
    time) when the controller offers no parameter service now."""
    client = node.create_client(SetParameters, f"{controller}/set_parameters")
    said: list[str] = []

    def switch(law: str) -> Future | None:
        if not client.service_is_ready():
            if not said:                  # asked again every tick until it is there
                said.append(law)
                node.get_logger().warning(f"controller switch to {law}: {controller} offers "
                                          "no parameter service yet (is it running?); asking "
                                          "again every tick until it does")
            return None
        if said:
            node.get_logger().info(f"{controller} is there: switching {law} on")
        return client.call_async(switch_on_request(law))
    return switch
