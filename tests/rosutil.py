"""Helpers for tests that start nodes: isolation, subprocess nodes, waiting for events."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import rclpy
from conftest import installed
from rclpy.node import Node


def isolate() -> int:
    """Give this test process (and the nodes it starts) its own DDS domain, loopback only:
    the two xdist workers of one run always get different domains (odd and even)."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    index = int(worker[2:]) if worker[2:].isdigit() else 0
    domain = 1 + 2 * (os.getpid() % 50) + index % 2
    os.environ["ROS_DOMAIN_ID"] = str(domain)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    return domain


def wait_for(condition: Callable[[], bool], node: Node, timeout_s: float, what: str) -> None:
    """Spin ``node`` until ``condition()`` holds; fail naming ``what`` after ``timeout_s``."""
    end = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout_s:g} s waiting for {what}")
        rclpy.spin_once(node, timeout_sec=0.01)


# services a repeated request does no harm to: their lost response is asked for again
REPEATABLE = ("GetParameters", "SetParameters", "SetBool", "ListParameters")


def call_service(node: Node, srv_type, name: str, request):
    """Call the service ``name`` once it is ready and wait for its response. The server's
    middleware drops a response when the client's response reader is not matched yet (it
    says "failed to send response (timeout)"; ros2/ros2#1253), which a loaded machine makes
    likelier on a first call: a repeatable request is then sent again, up to three times."""
    client = node.create_client(srv_type, name)
    wait_for(client.service_is_ready, node, 10.0, f"service {name}")
    attempts = 3 if srv_type.__name__ in REPEATABLE else 1
    for attempt in range(1, attempts + 1):
        future = client.call_async(request)
        try:
            wait_for(future.done, node, 10.0 if attempts == 1 else 5.0,
                     f"the {name} response" + (f" (attempt {attempt})" if attempts > 1 else ""))
            return future.result()
        except AssertionError:
            client.remove_pending_request(future)
            if attempt == attempts:
                raise
    raise AssertionError("unreachable")


def set_double(node: Node, target: str, name: str, value: float):
    """Set the double parameter ``name`` of node ``target``; the SetParametersResult."""
    from rcl_interfaces.msg import ParameterType, ParameterValue
    return _set(node, target, name, ParameterValue(type=ParameterType.PARAMETER_DOUBLE,
                                                   double_value=value))


def set_string(node: Node, target: str, name: str, value: str):
    """Set the string parameter ``name`` of node ``target``; the SetParametersResult."""
    from rcl_interfaces.msg import ParameterType, ParameterValue
    return _set(node, target, name, ParameterValue(type=ParameterType.PARAMETER_STRING,
                                                   string_value=value))


def _set(node: Node, target: str, name: str, value):
    from rcl_interfaces.msg import Parameter
    from rcl_interfaces.srv import SetParameters
    p = Parameter(name=name, value=value)
    return call_service(node, SetParameters, f"{target}/set_parameters",
                        SetParameters.Request(parameters=[p])).results[0]


def spin_for(node: Node, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.01)


class NodeProcess:
    """An installed console script run in a subprocess, stopped with SIGINT on exit."""

    def __init__(self, name: str, *args: str) -> None:
        self.proc = subprocess.Popen([installed(name), *args], stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, text=True, env=dict(os.environ))

    def stop(self, timeout_s: float = 10.0) -> tuple[int, str]:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
        try:
            out, _ = self.proc.communicate(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            out, _ = self.proc.communicate()
        return self.proc.returncode, out

    def __enter__(self) -> NodeProcess:
        return self

    def __exit__(self, kind, *exc) -> None:
        status, out = self.stop()
        if kind is not None:          # the test failed: what the program said, in its report
            print(f"--- {Path(self.proc.args[0]).name} (status {status}) said:\n{out}",
                  file=sys.stderr)
