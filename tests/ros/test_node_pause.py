"""Pause, step and reset at max speed with /clock, as msg_docs/node.md states them: paused,
nothing is published and the node waits (no core spent spinning); a step advances one tick of
simulated time (1/rate_hz at max speed) and publishes it; a reset publishes the initial state
at the same simulated time (it takes none) and stays paused; resuming goes on from there."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest
from geometry_msgs.msg import WrenchStamped
from rosgraph_msgs.msg import Clock
from rosutil import NodeProcess, call_service, spin_for, wait_for
from std_srvs.srv import SetBool, Trigger

RIG = "/maxpause/drill_sim"


def _cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _until_quiet(ros, *received: list, quiet_s: float = 0.5, timeout_s: float = 30.0) -> None:
    """Spin until nothing more has arrived for ``quiet_s``: the node's backlog at max speed is
    in (a loaded test process may take more than a second to drain it)."""
    end = time.monotonic() + timeout_s
    counts = None
    while time.monotonic() < end:
        now = tuple(len(r) for r in received)
        if now == counts:
            return
        counts = now
        spin_for(ros, quiet_s)
    raise AssertionError(f"still receiving after {timeout_s:g} s: the node did not pause")


def test_pause_step_reset_at_max_speed(ros):
    stamps: list[float] = []
    clocks: list[float] = []
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/maxpause", "-p",
                     "publish_clock:=true", "-p", "max_speed:=true", "-p", "rate_hz:=100.0",
                     "-p", "real_time_factor:=3.0") as proc:
        ros.create_subscription(WrenchStamped, f"{RIG}/bit/wrench", lambda m: stamps.append(
            m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec), 1000)
        ros.create_subscription(Clock, "/clock", lambda m: clocks.append(
            m.clock.sec + 1e-9 * m.clock.nanosec), 1000)
        wait_for(lambda: len(stamps) > 100, ros, 30.0, "the rig at max speed")

        def call(srv, name, request):
            return call_service(ros, srv, f"{RIG}/{name}", request)

        assert call(SetBool, "pause", SetBool.Request(data=True)).success
        _until_quiet(ros, stamps, clocks)         # what was on its way arrives (under load late)
        stamps.clear()
        clocks.clear()
        cpu0 = _cpu_s(proc.proc.pid)
        spin_for(ros, 2.0)
        assert stamps == [] and clocks == []      # nothing published while paused
        assert _cpu_s(proc.proc.pid) - cpu0 < 1.0  # waiting, not spinning a core for 2 s

        assert call(Trigger, "step", Trigger.Request()).success
        wait_for(lambda: len(stamps) == 1, ros, 10.0, "the stepped sample")
        assert call(Trigger, "step", Trigger.Request()).success
        wait_for(lambda: len(stamps) == 2, ros, 10.0, "a second stepped sample")
        assert stamps[1] - stamps[0] == pytest.approx(0.01, abs=2e-4)   # one tick: 1/rate_hz
        assert clocks[-1] == pytest.approx(stamps[1])

        reset = call(Trigger, "reset", Trigger.Request())
        assert reset.success
        wait_for(lambda: len(stamps) == 3, ros, 10.0, "the reset's sample")
        assert stamps[2] == stamps[1]             # a reset takes no simulated time
        spin_for(ros, 0.5)
        assert len(stamps) == 3                   # and the node is still paused

        assert call(SetBool, "pause", SetBool.Request(data=False)).message == "running"
        wait_for(lambda: len(stamps) > 50, ros, 10.0, "outputs after resuming")
        assert stamps[3] == pytest.approx(stamps[2] + 0.01, abs=2e-4)   # on from there
