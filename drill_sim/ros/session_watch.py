"""The ROS side of ``drill_sim run``: start the rig node and its clients (a controller) as
subprocesses, watch the rig's samples with a ``Monitor`` for the session's length (a status
line as it goes), and refuse to mix with another rig of the same name on the domain."""

from __future__ import annotations

import os
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass

import rclpy
from rclpy.executors import SingleThreadedExecutor

from ..bag.series import RigSeries
from .monitor import Monitor
from .stopping import stop_processes
from .topics import NOT_YET_NAMED

DISCOVERY_S = 0.5        # before the rig starts: how long to look for a rig already running
OTHER_RIG_LOOK_S = 0.5   # during the session: how often to look for a second rig


@dataclass(frozen=True)
class Watched:
    """How a watched session ended: ``others``, the other rigs found on the session's topics
    (fully qualified node names; then nothing or not all was run); ``node_exit``, the node's
    exit status if it stopped by itself; ``received``, the samples the monitor received;
    ``topic``, the samples' topic."""

    others: tuple[str, ...]
    node_exit: int | None
    received: RigSeries
    topic: str


class OtherRig(Exception):
    """Another rig publishes on the session rig's topics (names: fully qualified nodes)."""


def watch_session(node_cmd: list[str], clients: list[list[str]], duration_s: float, tty: bool,
                  status: Callable[[Monitor], str | None]) -> Watched:
    """Run the node, then (once it publishes) the ``clients``, for
    ``duration_s`` wall seconds (+2 s); ``status(monitor)`` gives the live status line.
    Every process is stopped at the end: the clients first, then the rig."""
    env = dict(os.environ)
    rclpy.init()
    monitor = Monitor()
    executor = SingleThreadedExecutor()
    executor.add_node(monitor)
    # a rig of this name already on the domain would mix with this session's: look before
    # starting one (discovery of a local rig mostly takes ~0.05 s), and all along the session
    # (it may take ~3 s)
    end = time.monotonic() + DISCOVERY_S
    while time.monotonic() < end and not monitor.other_rigs(first_included=True):
        executor.spin_once(timeout_sec=0.02)
    end = time.monotonic() + DISCOVERY_S          # found: its name may come a moment later
    while NOT_YET_NAMED in monitor.other_rigs(first_included=True) and time.monotonic() < end:
        executor.spin_once(timeout_sec=0.02)
    others = monitor.other_rigs(first_included=True)
    procs = [] if others else [subprocess.Popen(node_cmd, env=env)]
    node_exit = None
    try:
        # the clients start once the rig publishes: a node that refuses its parameters has
        # printed its one line and run ends there, with the node's status 2
        while not others and monitor.count == 0 and node_exit is None:
            executor.spin_once(timeout_sec=0.05)
            node_exit = procs[0].poll()
        if not others and node_exit is None:
            procs += [subprocess.Popen(cmd, env=env) for cmd in clients]
            node_exit = _live(executor, monitor, procs[0], duration_s, tty, status)
    except KeyboardInterrupt:
        pass
    except OtherRig as exc:
        others = exc.args[0]
    finally:
        if tty:
            print()
        # the clients first, then the rig: a controller in charge of the drive hands it back
        # to the rig's speed loop as it stops, which needs the rig still there
        stop_processes(procs[1:])
        stop_processes(procs[:1])
        received = monitor.series()
        executor.shutdown()
        monitor.destroy_node()
        rclpy.try_shutdown()
    return Watched(tuple(others), node_exit, received, monitor.topic)


def _live(executor, monitor: Monitor, node: subprocess.Popen, duration: float, tty: bool,
          status: Callable[[Monitor], str | None]) -> int | None:
    """Spin the monitor for ``duration`` (+2 s) with the status line; the node's exit status
    if it stopped meanwhile. Raises OtherRig when a second rig appears on the session's
    topics (discovery of one already running may take ~3 s)."""
    start = time.monotonic()
    last_print = last_look = 0.0
    while time.monotonic() - start < duration + 2.0:
        executor.spin_once(timeout_sec=0.02)
        if node.poll() is not None:
            return node.returncode
        now = time.monotonic()
        if now - last_look > OTHER_RIG_LOOK_S:
            last_look = now
            if others := monitor.other_rigs():
                raise OtherRig(others)
        if now - last_print > (0.2 if tty else 5.0):
            last_print = now
            line = status(monitor)
            if line is not None:
                print(("\r" + line) if tty else line, end="" if tty else "\n", flush=True)
    return None
