"""Rig nodes started for one test each (own namespace): start-up errors, sim time, signals,
the scenario driver, diagnostics. Kept apart from test_node.py so that module's long-running
rig does not compete for the CPU with these timing checks."""

from __future__ import annotations

import queue
import threading
import time

import numpy as np
import pytest
import rclpy
from geometry_msgs.msg import WrenchStamped
from rosgraph_msgs.msg import Clock
from rosutil import NodeProcess, set_double, spin_for, wait_for
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool

from drill_sim.core import RPM


def test_bad_startup_parameter_exits_with_a_clear_message(ros):
    proc = NodeProcess("drill_sim_node", "--ros-args", "-p", "initial_state:=sideways")
    code = proc.proc.wait(timeout=30)
    out = proc.proc.stdout.read()
    assert code == 2 and "initial_state" in out and "Traceback" not in out


_LINES: dict[int, queue.Queue] = {}


def _pump(stream, lines: queue.Queue) -> None:
    """Every line of ``stream`` into ``lines``, then "" once it ends (or is closed)."""
    try:
        for line in iter(stream.readline, ""):
            lines.put(line)
    except (OSError, ValueError):
        pass
    lines.put("")


def _line_with(proc: NodeProcess, text: str, timeout_s: float = 30.0) -> str | None:
    """The first line of the process's output that holds ``text``, read as it comes (by a
    thread: a select() on the pipe misses lines already in the reader's buffer when several
    came in one write)."""
    lines = _LINES.get(proc.proc.pid)
    if lines is None:
        lines = _LINES[proc.proc.pid] = queue.Queue()
        threading.Thread(target=_pump, args=(proc.proc.stdout, lines), daemon=True).start()
    end = time.monotonic() + timeout_s
    while (left := end - time.monotonic()) > 0:
        try:
            line = lines.get(timeout=left)
        except queue.Empty:
            return None
        if text in line:
            return line
        if not line:                                  # the process ended
            return None
    return None


@pytest.mark.parametrize("program", ["drill_sim_node", "drill_sim_controller"])
def test_a_misspelled_parameter_is_named_with_the_nearest(ros, program):
    """ROS ignores a parameter a node never declared; the node says so, with the name it
    likely meant, and runs on."""
    wrong, meant = ("rate", "rate_hz") if program == "drill_sim_node" else ("lw", "law")
    with NodeProcess(program, "--ros-args", "-r", "__ns:=/typo", "-p", f"{wrong}:=100",
                     "-p", "qos_overrides./x.publisher.depth:=5") as proc:
        line = _line_with(proc, "is not one of")
        assert line is not None and f"parameter '{wrong}' is not one of" in line, line
        assert f"did you mean '{meant}'?" in line and "[WARN]" in line
        assert proc.proc.poll() is None                  # a warning, not a refusal
        assert _line_with(proc, "qos_overrides", timeout_s=1.0) is None
        if program == "drill_sim_node":    # at run time: refused by rclpy, named in the log
            result = set_double(ros, "/typo/drill_sim", "raet_hz", 500.0)
            assert not result.successful
            line = _line_with(proc, "refused: drill_sim has no such parameter")
            assert line is not None and "'raet_hz'" in line and "'rate_hz'?" in line, line


def test_sim_time_mode_publishes_clock_ten_times_faster(ros):
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/fast", "-p",
                     "publish_clock:=true", "-p", "real_time_factor:=10.0"):
        clocks: list[tuple[float, float]] = []
        stamps: list[float] = []
        ros.create_subscription(
            Clock, "/clock", lambda m: clocks.append(
                (rclpy.clock.Clock().now().nanoseconds * 1e-9,
                 m.clock.sec + 1e-9 * m.clock.nanosec)), 1000)
        ros.create_subscription(
            WrenchStamped, "/fast/drill_sim/bit/wrench",
            lambda m: stamps.append(m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec), 1000)
        wait_for(lambda: len(clocks) > 10 and len(stamps) > 10, ros, 30.0, "/clock and outputs")
        spin_for(ros, 2.0)
        wall = np.array(clocks)
        rate = (wall[-1, 1] - wall[0, 1]) / (wall[-1, 0] - wall[0, 0])
        assert rate == pytest.approx(10.0, rel=0.1)
        # stamps are /clock times (a loaded subscriber may drop some /clock messages): each
        # within one tick (10 ms simulated at 1 kHz x 10) of a received one, most exactly one
        clock = np.sort(wall[:, 1])
        recent = np.array(stamps[-500:])
        idx = np.clip(np.searchsorted(clock, recent), 1, clock.size - 1)
        gap = np.minimum(np.abs(clock[idx] - recent), np.abs(clock[idx - 1] - recent))
        assert np.all(gap <= 0.0101)
        published = {round(c, 9) for c in clock}
        assert np.mean([round(s, 9) in published for s in recent]) > 0.5
        assert stamps[-1] < 60.0                                      # sim time from zero


def test_sigterm_shuts_down_cleanly(ros):
    import signal
    proc = NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/term")
    seen: list[float] = []
    sub = ros.create_subscription(Bool, "/term/drill_sim/bit/stick_slip",
                                  lambda m: seen.append(1.0), 10)
    wait_for(lambda: len(seen) > 5, ros, 30.0, "the namespaced rig's outputs")
    proc.proc.send_signal(signal.SIGTERM)
    code = proc.proc.wait(timeout=20)
    out = proc.proc.stdout.read()
    ros.destroy_subscription(sub)
    assert code == 0 and "Traceback" not in out and "shut down" in out, out
    assert "rig figures: W_s 338 kN, t* 0.210 s, torsional 0.756 Hz" in out   # at start


def test_driver_plays_a_scenario_onto_the_rig(ros, base):
    """drill_sim_drive against its own namespaced rig: commanded speed follows the scenario."""
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/drive", "-p",
                     "real_time_factor:=1.0"), \
            NodeProcess("drill_sim_drive", "step_test", "--ros-args", "-r", "__ns:=/drive"):
        speeds: list[float] = []
        ros.create_subscription(JointState, "/drive/drill_sim/joint_states",
                                lambda m: speeds.append(m.velocity[0]), 100)
        wait_for(lambda: len(speeds) > 100, ros, 30.0, "the driven rig's joint states")
        wait_for(lambda: speeds[-1] == pytest.approx(120 * RPM), ros, 30.0,
                 "the scenario's 120 rpm step at 10 s")


def test_stale_commands_are_reported_on_diagnostics(ros):
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/stale", "-r",
                     "__node:=stale_rig", "-p", "command_timeout_s:=0.2"):
        seen: list = []
        sub = ros.create_subscription(DiagnosticArray, "/diagnostics", lambda m: seen.extend(
            s for s in m.status if s.name.startswith("stale_rig")), 10)
        wait_for(lambda: any(s.level == DiagnosticStatus.WARN for s in seen), ros, 30.0,
                 "a WARN status from the rig that got no command")
        warn = next(s for s in seen if s.level == DiagnosticStatus.WARN)
        values = {kv.key: kv.value for kv in warn.values}
        ros.destroy_subscription(sub)
    assert "no command" in warn.message
    assert float(values["command_age_s"]) > 0.2
    assert {"tick_rate_hz", "tick_period_p99_ms", "overruns", "real_time_factor", "regime",
            "ssi"} <= set(values)


def test_a_stalled_node_still_publishes_every_tick(ros):
    """The node stopped (SIGSTOP) for ~2.5 ms, twenty times, as a busy machine stalls it:
    each stall's ticks still come, each with its own sample, so the stamps go on 1 ms
    apart: no gap of 2 to CATCH_UP_TICKS ticks (a stall the machine stretched beyond that
    may leave one longer gap). Advancing the missed ticks with one sample, as the node did,
    left a 3-4 ms gap at every stall; the diagnostics still count the stalls."""
    import os
    import signal
    import threading

    from diagnostic_msgs.msg import DiagnosticArray

    from drill_sim.session.pacing import CATCH_UP_TICKS
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/stalled", "-r",
                     "__node:=stalled_rig") as rig:
        stamps_ns: list[int] = []
        overruns: list[int] = []
        subs = [ros.create_subscription(JointState, "/stalled/stalled_rig/joint_states",
                                        lambda m: stamps_ns.append(
                                            m.header.stamp.sec * 10**9 + m.header.stamp.nanosec),
                                        1000),
                ros.create_subscription(DiagnosticArray, "/diagnostics", lambda m: overruns.extend(
                    int(kv.value) for s in m.status if s.name.startswith("stalled_rig")
                    for kv in s.values if kv.key == "overruns"), 10)]
        wait_for(lambda: len(stamps_ns) > 500, ros, 30.0, "the stalled rig's samples")

        def stall() -> None:
            for _ in range(20):
                time.sleep(0.05)
                os.kill(rig.proc.pid, signal.SIGSTOP)
                time.sleep(0.0025)
                os.kill(rig.proc.pid, signal.SIGCONT)

        stamps_ns.clear()
        stalls = threading.Thread(target=stall)
        stalls.start()
        while stalls.is_alive():
            rclpy.spin_once(ros, timeout_sec=0.001)
        first = len(overruns)
        wait_for(lambda: len(overruns) > first + 1, ros, 10.0, "the rig's diagnostics after")
        for sub in subs:
            ros.destroy_subscription(sub)
    steps = np.round(np.diff(np.array(stamps_ns)) / 1e6).astype(int)    # in ticks of 1 ms
    assert len(steps) > 900
    assert overruns[-1] >= 10                         # the node saw the stalls
    gaps = steps[(steps > 1) & (steps <= CATCH_UP_TICKS)]
    assert gaps.size == 0, f"samples missing after stalls: gaps of {gaps.tolist()} ticks"
    assert (steps == 1).mean() > 0.97 and steps.min() == 1


def _policy(stat: str) -> tuple[int, int]:
    """(scheduling policy, real-time priority) from a /proc .../stat line."""
    fields = stat.rsplit(")", 1)[1].split()
    return int(fields[38]), int(fields[37])          # fields 41 and 40 of proc(5)


def test_a_second_rig_of_the_same_name_is_named_by_both(ros):
    """Two rigs started under one name on one domain publish on the same topics, and every
    subscriber mixes their samples: each says so (log and /diagnostics), naming the other,
    and the first says when it is the only one again."""
    from diagnostic_msgs.msg import DiagnosticArray
    warned: list[str] = []
    sub = ros.create_subscription(DiagnosticArray, "/diagnostics", lambda m: warned.extend(
        s.message for s in m.status if s.name == "drill_sim: rig" and "other publisher"
        in s.message), 10)
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/dup") as first:
        assert _line_with(first, "ready") is not None
        with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/dup") as second:
            for rig in (first, second):
                line = _line_with(rig, "other publisher on this rig's ~/joint_states")
                assert line is not None and "(/dup/drill_sim)" in line and "[ERROR]" in line
            wait_for(lambda: bool(warned), ros, 10.0, "the warning on /diagnostics")
            assert "another rig of the same name or a replay" in warned[0]
        assert _line_with(first, "this rig is its only publisher again") is not None
    ros.destroy_subscription(sub)


def test_two_programs_commanding_one_rig_are_named_in_the_log_and_on_diagnostics(ros):
    """Two nodes publishing on the rig's ~/cmd/top_drive: the rig warns once, naming both,
    counts the topic on /diagnostics while it lasts, and says when one publisher is left."""
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import TwistStamped
    seen: list[dict[str, str]] = []
    sub = ros.create_subscription(DiagnosticArray, "/diagnostics", lambda m: seen.extend(
        {**{v.key: v.value for v in s.values}, "message": s.message} for s in m.status
        if s.name == "drill_sim: rig"), 10)
    other = rclpy.create_node("second_driller")
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/two") as rig:
        assert _line_with(rig, "ready") is not None
        pubs = [n.create_publisher(TwistStamped, "/two/drill_sim/cmd/top_drive", 10)
                for n in (ros, other)]
        line = _line_with(rig, "2 publishers on ~/cmd/top_drive")
        assert line is not None and "[WARN]" in line, line
        assert f"/{ros.get_name()}" in line and "/second_driller" in line, line
        wait_for(lambda: any(d.get("command_topics_with_several_publishers")
                             == "~/cmd/top_drive" for d in seen), ros, 10.0,
                 "the shared command topic on /diagnostics")
        assert any("2 publishers on ~/cmd/top_drive" in d["message"] for d in seen)
        other.destroy_publisher(pubs[1])
        assert _line_with(rig, "~/cmd/top_drive: one publisher again") is not None
    other.destroy_node()
    ros.destroy_subscription(sub)


def test_command_owner_first_takes_one_publishers_commands_and_names_the_refused(ros):
    """command_owner:=first: the first publisher on ~/cmd/top_drive owns it; a second node's
    commands are refused (the top drive keeps the owner's speed), named in the log with the
    owner, counted on /diagnostics; when the owner's publisher leaves, the next publisher's
    command takes the topic. Fails if the rig applies the intruder's speed or cannot tell
    the two publishers apart (one GID for both: nothing refused)."""
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import TwistStamped
    owner_name, intruder = f"/{ros.get_name()}", rclpy.create_node("intruding_driller")
    seen: list[dict[str, str]] = []
    speeds: list[float] = []
    subs = [ros.create_subscription(DiagnosticArray, "/diagnostics", lambda m: seen.extend(
        {v.key: v.value for v in s.values} for s in m.status
        if s.name == "drill_sim: rig"), 10),
        ros.create_subscription(TwistStamped, "/own/drill_sim/top_drive/twist",
                                lambda m: speeds.append(m.twist.angular.z), 100)]

    def command(pub, speed_rad_s: float, node=None) -> None:
        msg = TwistStamped()
        msg.twist.angular.z = speed_rad_s
        pub.publish(msg)
        spin_for(node or ros, 0.02)

    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/own",
                     "-p", "command_owner:=first", "-p", "diagnostics_period_s:=0.2") as rig:
        assert _line_with(rig, "ready") is not None
        mine = ros.create_publisher(TwistStamped, "/own/drill_sim/cmd/top_drive", 10)
        theirs = intruder.create_publisher(TwistStamped, "/own/drill_sim/cmd/top_drive", 10)
        wait_for(lambda: mine.get_subscription_count() and theirs.get_subscription_count(),
                 ros, 10.0, "the rig's command subscription")
        command(mine, 5.0)
        line = _line_with(rig, "~/cmd/top_drive: taking only")
        assert line is not None and f"{owner_name}'s commands" in line, line
        for _ in range(5):          # until the graph has named the intruder (a report a second)
            for _ in range(20):
                command(theirs, 9.0, intruder)
                command(mine, 5.0)
            line = _line_with(rig, "refused")
            if line is None or "from /intruding_driller" in line:
                break
        assert line is not None and "from /intruding_driller" in line, line
        assert f"{owner_name} owns it" in line and "[WARN]" in line, line
        speeds.clear()
        for _ in range(10):
            command(theirs, 9.0, intruder)
        spin_for(ros, 0.3)
        assert speeds and all(abs(w - 5.0) < 1e-9 for w in speeds), speeds[-5:]
        wait_for(lambda: any(int(d.get("commands_refused", "0")) >= 20 and d.get(
            "command_owners") == f"~/cmd/top_drive={owner_name}" for d in seen), ros, 10.0,
            "the refusals and the owner on /diagnostics")
        ros.destroy_publisher(mine)
        line = _line_with(rig, "its owner")
        assert line is not None and f"{owner_name} has left" in line, line
        command(theirs, 9.0, intruder)
        line = _line_with(rig, "~/cmd/top_drive: taking only")
        assert line is not None and "/intruding_driller's commands" in line, line
        wait_for(lambda: speeds and abs(speeds[-1] - 9.0) < 1e-9, ros, 10.0,
                 "the new owner's speed at the top drive")
    for sub in subs:
        ros.destroy_subscription(sub)
    intruder.destroy_node()


def test_cpu_wakeup_latency_is_requested_while_the_node_runs_and_withdrawn_after(ros):
    """cpu_wakeup_latency_us:=7: while the installed node runs it holds the kernel's CPU
    latency request open with 7 us (the limit in force is then at most 7), and once it has
    stopped the machine's limit is what it was; or, where the system refuses (not root), a
    warning saying what would allow it."""
    import os
    from pathlib import Path

    from drill_sim.ros.wakeups import CPU_LATENCY_DEVICE, cpu_latency_now_us
    before = cpu_latency_now_us()
    seen: list[int] = []
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/qos_latency",
                     "-p", "cpu_wakeup_latency_us:=7") as rig:
        sub = ros.create_subscription(JointState, "/qos_latency/drill_sim/joint_states",
                                      lambda m: seen.append(1), 10)
        wait_for(lambda: len(seen) > 20, ros, 30.0, "the rig's samples")
        fds = Path(f"/proc/{rig.proc.pid}/fd")
        held = [fd for fd in fds.iterdir() if os.path.realpath(fd) == CPU_LATENCY_DEVICE]
        during = cpu_latency_now_us()
        code, out = rig.stop()
        ros.destroy_subscription(sub)
    assert code == 0, out
    if before is None:                               # not root: refused, and said why
        assert "cpu_wakeup_latency_us 7 not taken" in out and not held, out
        return
    assert "wake-ups of at most 7 us" in out and len(held) == 1, out
    assert during <= 7                               # the least of all requests
    assert cpu_latency_now_us() == before            # withdrawn with the node


@pytest.mark.parametrize("mode", ["real_time", "max_speed"])
def test_thread_priority_puts_the_loop_under_sched_fifo(ros, mode):
    """thread_priority:=10: the loop's thread (the main one) under SCHED_FIFO 10, the
    middleware's threads left as they were; or, where the system refuses, a warning saying
    what would allow it. Not at max speed (a loop that never sleeps would starve the machine)."""
    import os
    from pathlib import Path
    extra = ["-p", "publish_clock:=true", "-p", "max_speed:=true"] if mode == "max_speed" else []
    seen: list[int] = []
    with NodeProcess("drill_sim_node", "--ros-args", "-r", f"__ns:=/prio_{mode}",
                     "-p", "thread_priority:=10", *extra) as rig:
        sub = ros.create_subscription(JointState, f"/prio_{mode}/drill_sim/joint_states",
                                      lambda m: seen.append(1), 10)
        wait_for(lambda: len(seen) > 20, ros, 30.0, "the rig's samples")
        tasks = Path(f"/proc/{rig.proc.pid}/task")
        policies = {int(t.name): _policy((t / "stat").read_text()) for t in tasks.iterdir()}
        code, out = rig.stop()
        ros.destroy_subscription(sub)
    assert code == 0, out
    main, others = policies.pop(rig.proc.pid), set(policies.values())
    if mode == "max_speed":
        assert "not taken at max speed" in out and main == (os.SCHED_OTHER, 0), out
    elif "ticking under SCHED_FIFO, priority 10" in out:
        assert main == (os.SCHED_FIFO, 10)
        assert others == {(os.SCHED_OTHER, 0)}           # the middleware's threads: as they were
    else:
        assert "thread_priority 10 not taken" in out and main == (os.SCHED_OTHER, 0), out
