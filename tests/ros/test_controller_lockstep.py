"""The offline loop and the nodes in lockstep are the same loop: the installed rig node (torque
mode, lockstep on its motor-torque command) and drill_sim_controller give, sample by sample, the
bit speed and motor torque ``drill_sim.control.closed_loop.run_loop`` computes in-process for the
same law, gains, sample instants and start (steady at 60 rpm, set-point 61 rpm: a transient
that the law must work through, its integral off the limits)."""

from __future__ import annotations

import math
import re

import numpy as np
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rosutil import NodeProcess, call_service, wait_for
from std_srvs.srv import SetBool

from drill_sim.control.closed_loop import run_loop
from drill_sim.control.evaluation import LoopSettings, Scenario
from drill_sim.control.reference import reference_gains
from drill_sim.core import RPM, load_preset

NS = "/ctlock"
RIG = f"{NS}/drill_sim"
DURATION_S = 1.5


def stamp(m) -> int:
    """A message's header stamp [ns]."""
    return m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec


def by_stamp(ros, rig: str, bit: bool = True) -> tuple[dict[int, float], dict[int, float]]:
    """The rig's bit speed [rad/s] (if ``bit``) and motor torque [N m], by stamp, as they
    come."""
    bit_speed: dict[int, float] = {}
    motor: dict[int, float] = {}
    if bit:
        ros.create_subscription(TwistStamped, f"{rig}/bit/twist",
                                lambda m: bit_speed.__setitem__(stamp(m), m.twist.angular.z),
                                10000)
    ros.create_subscription(WrenchStamped, f"{rig}/top_drive/motor_wrench",
                            lambda m: motor.__setitem__(stamp(m), m.wrench.torque.z), 10000)
    return bit_speed, motor


def lockstep_rig(ns: str, *params: str) -> NodeProcess:
    """The installed rig in namespace ``ns``: on its /clock, in lockstep on the motor-torque
    command, started paused; ``params``: more ``name:=value``."""
    args = ["top_drive_mode:=torque", "publish_clock:=true", "lockstep:=true",
            "lockstep_topics:=[cmd/top_drive_torque]", "lockstep_timeout_s:=0.5",
            "start_paused:=true", *params]
    return NodeProcess("drill_sim_node", "--ros-args", "-r", f"__ns:={ns}",
                       *(a for p in args for a in ("-p", p)))


def start_when_connected(ros, rig: str) -> None:
    """Unpause the rig once the controller publishes to it and listens to it."""
    wait_for(lambda: ros.count_publishers(f"{rig}/cmd/top_drive_torque") > 0
             and ros.count_subscribers(f"{rig}/top_drive/motor_wrench") >= 2
             and ros.count_publishers(f"{rig}/top_drive/motor_wrench") > 0
             and ros.count_publishers(f"{rig}/bit/twist") > 0, ros, 60.0,
             "the rig and the controller connected")
    assert call_service(ros, SetBool, f"{rig}/pause", SetBool.Request(data=False)).success


def recorded_commands(bag, topic: str, kind, value) -> dict[int, float]:
    """The commands on ``topic`` as the rig took them (its bag records every command it
    takes; a test's own subscription may miss some on a loaded machine), by stamp."""
    from rclpy.serialization import deserialize_message

    from drill_sim.bag.reader import read_messages
    out = {}
    for m in read_messages(bag):
        if m.topic == topic:
            msg = deserialize_message(m.data, kind)
            out[stamp(msg)] = value(msg)
    return out


def test_lockstep_nodes_reproduce_the_offline_loop(ros):
    preset = load_preset("base")
    gains = reference_gains("z_torque", preset, 2900.0)
    bit, motor = by_stamp(ros, RIG)
    controller = ["-p", f"rig:={RIG}", "-p", "inputs:=exact",
                  "-p", f"initial_speed_setpoint_rad_s:={61 * RPM!r}",
                  *(a for k, v in gains.items() for a in ("-p", f"z_torque.{k}:={float(v)!r}"))]
    with lockstep_rig(NS), \
         NodeProcess("drill_sim_controller", "--ros-args", "-r", f"__ns:={NS}", *controller):
        start_when_connected(ros, RIG)
        wait_for(lambda: bit and motor and min(max(bit), max(motor)) * 1e-9 >= DURATION_S,
                 ros, 240.0,
                 f"{DURATION_S} s of lockstep ticks")
    offline = run_loop(preset, Scenario.of_points("step", ((0.0, 61.0),), ((0.0, 100.0),),
                                                  duration_s=DURATION_S, window_start_s=0.5,
                                                  start_rpm=60.0),
                       LoopSettings(law="z_torque", gains=gains, perturbation=0.0))
    n = len(offline.series["time_s"])
    stamps = sorted(bit)[:n]
    assert len(stamps) == n and stamps == [k * 1_000_000 for k in range(n)]   # every tick
    ros_bit = np.array([bit[s] for s in stamps])
    ros_motor = np.array([motor[s] for s in stamps])
    off_bit, off_motor = offline.series["bit_speed_rad_s"], offline.series["motor_torque_nm"]
    assert np.ptp(off_motor) > 30.0 and np.ptp(off_bit) > 5e-3      # the transient is real
    assert np.allclose(ros_bit, off_bit, rtol=0.0, atol=1e-9 * math.tau)
    assert np.allclose(ros_motor, off_motor, rtol=1e-12, atol=1e-6)


def test_a_disabled_controller_answers_each_lockstep_tick_with_a_hold(ros, tmp_path):
    """``enabled:=false`` (the drive in torque mode, not managed): the rig in lockstep still
    advances, every tick answered by the controller with the torque the drive applies (a
    hold), as a rig in real time keeps its last command; the motor torque stays put. The
    rig's bag keeps what the controller reported: its law, its gains, that it was off."""
    import json
    import subprocess

    from conftest import installed
    from diagnostic_msgs.msg import DiagnosticArray
    reports: list[str] = []
    ros.create_subscription(DiagnosticArray, "/diagnostics", lambda m: reports.extend(
        s.name for s in m.status if s.name.endswith(": controller")), 10)
    bag = tmp_path / "off"
    ns, rig = "/ctoff", "/ctoff/drill_sim"
    _, motor = by_stamp(ros, rig, bit=False)
    with lockstep_rig(ns, "lockstep_timeout_s:=5.0", f"record:={bag}"), \
         NodeProcess("drill_sim_controller", "--ros-args", "-r", f"__ns:={ns}",
                     "-p", f"rig:={rig}", "-p", "inputs:=exact", "-p", "enabled:=false"):
        start_when_connected(ros, rig)
        # 300 ticks in lockstep: far fewer than one lockstep timeout of 5 s would allow
        wait_for(lambda: len(motor) >= 300, ros, 60.0, "300 lockstep ticks")
        first = len(reports)
        wait_for(lambda: len(reports) > first + 1, ros, 10.0, "the controller's reports")
    ticks = sorted(motor)[:300]
    done = subprocess.run([installed("drill_sim"), "bag", "diagnostics", str(bag), "--name",
                           ": controller", "--json"], capture_output=True, text=True,
                          timeout=60)
    recorded = [json.loads(line) for line in done.stdout.splitlines()]
    assert recorded, done.stdout + done.stderr
    values = recorded[-1]["values"]
    assert values["law"] == "z_torque" and values["enabled"] == "False"
    assert json.loads(values["gains"])["alpha"] > 0.0
    assert ticks == [k * 1_000_000 for k in range(300)]
    answers = recorded_commands(bag, f"{rig}/cmd/top_drive_torque", WrenchStamped,
                                lambda m: m.wrench.torque.z)
    assert all(t in answers for t in ticks)
    assert np.allclose([answers[t] for t in ticks], motor[0], rtol=1e-12)   # a hold
    assert np.ptp([motor[t] for t in ticks]) < 1e-9 * abs(motor[0]) + 1e-9


def test_a_managed_controller_disabled_in_lockstep_answers_with_its_set_point(ros, tmp_path):
    """manage_drive_mode, the rig in lockstep on the motor-torque command: disabled, the
    controller hands the drive back to its speed loop and answers every tick with the
    set-point it was handed (from its own set-point topic) on the rig's ~/cmd/top_drive, where
    the rig's wait has moved with the drive's mode; enabled again, the law's torque answers.
    Every tick is answered: no tick after the first waits out the lockstep timeout (3 s), and
    the drive's speed goes to the set-point. Fails if the disabled controller is silent (the
    rig waits, as before), or answers a torque the speed-mode drive refuses."""
    from rcl_interfaces.msg import ParameterType, ParameterValue
    from rosutil import _set, spin_for
    ns, rig, bag = "/ctman", "/ctman/drill_sim", tmp_path / "managed"
    _, motor = by_stamp(ros, rig, bit=False)
    drive: dict[int, float] = {}
    ros.create_subscription(TwistStamped, f"{rig}/top_drive/twist",
                            lambda m: drive.__setitem__(stamp(m), m.twist.angular.z), 10000)
    law: dict[int, float] = {}
    ros.create_subscription(WrenchStamped, f"{rig}/cmd/top_drive_torque",
                            lambda m: law.__setitem__(stamp(m), m.wrench.torque.z), 10000)
    setpoint = ros.create_publisher(TwistStamped, "/ctman_setpoint", 10)
    with lockstep_rig(ns, "top_drive_mode:=speed", "lockstep_timeout_s:=3.0",
                      f"record:={bag}") as node, \
         NodeProcess("drill_sim_controller", "--ros-args", "-r", f"__ns:={ns}",
                     "-p", f"rig:={rig}", "-p", "inputs:=exact", "-p", "manage_drive_mode:=true",
                     "-p", "setpoint_topic:=/ctman_setpoint",
                     "-p", f"initial_speed_setpoint_rad_s:={60 * RPM!r}"):
        start_when_connected(ros, rig)
        wait_for(lambda: len(motor) >= 200, ros, 60.0, "200 ticks under the law")
        msg = TwistStamped()
        msg.twist.angular.z = 65 * RPM
        setpoint.publish(msg)
        spin_for(ros, 0.2)
        off = ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=False)
        assert _set(ros, f"{ns}/drill_sim_controller", "enabled", off).successful
        at_off = max(motor)
        wait_for(lambda: max(motor) >= at_off + 1_500_000_000, ros, 60.0,
                 "1.5 s of ticks with the controller off")
        on = ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=True)
        assert _set(ros, f"{ns}/drill_sim_controller", "enabled", on).successful
        at_on = max(motor)
        # the drive's mode moves back through a parameter call to the rig, which takes
        # longer on a loaded machine: wait for the law's torques themselves
        wait_for(lambda: sum(t > at_on for t in law) > 250, ros, 60.0,
                 "250 of the law's torques with the controller on again")
        _, out = node.stop()
    # the first tick may be published before the controller's subscription is matched (the
    # rig publishes it again after the timeout); no later tick waits
    waited = re.findall(r"lockstep: waiting [\d.]+ s for a command stamped ([\d.]+) s", out)
    assert all(float(w) == 0.0 for w in waited), out[-2000:]
    speeds = recorded_commands(bag, f"{rig}/cmd/top_drive", TwistStamped,
                               lambda m: m.twist.angular.z)
    off_ticks = [t for t in sorted(motor) if at_off + 300_000_000 <= t <= at_on]
    assert len(off_ticks) > 1000
    assert all(speeds.get(t) == 65 * RPM for t in off_ticks)      # each tick: the set-point
    late = [drive[t] for t in off_ticks[len(off_ticks) // 2:] if t in drive]
    assert abs(np.mean(late) - 65 * RPM) < 0.05 * 65 * RPM     # the drive's loop follows it
    torques = recorded_commands(bag, f"{rig}/cmd/top_drive_torque", WrenchStamped,
                                lambda m: m.wrench.torque.z)
    assert sum(t > at_on for t in torques) > 200                  # the law answers again


def _policy_offline(policy, duration_s: float) -> tuple[np.ndarray, np.ndarray]:
    """The policy through the Gymnasium environment at the rig's 1 ms: bit speed and motor
    torque at every sample, the start and set-point of the lockstep runs above."""
    from drill_sim.gym import RigEnv
    env = RigEnv("base", control_period_s=1e-3, perturbation=0.0, scenarios=[
        Scenario.of_points("step", ((0.0, 61.0),), ((0.0, 100.0),), duration_s=duration_s,
                           window_start_s=0.5, start_rpm=60.0)])
    obs, _ = env.reset(seed=0)
    truncated = False
    while not truncated:
        obs, _, _, truncated, _ = env.step(policy(obs))
    series = env.loop.series
    return series["bit_speed_rad_s"], series["motor_torque_nm"]


def test_one_policy_in_the_environment_and_against_the_nodes_gives_the_same_samples(ros):
    """``-p law:=policy -p policy:=drill_sim.control.policy:proportional_speed_policy``: the
    controller node runs the very callable the environment ran offline, and the rig in
    lockstep gives the same bit speed and motor torque at every sample (to 1e-9)."""
    from drill_sim.control.policy import proportional_speed_policy
    ns, rig, duration = "/ctpol", "/ctpol/drill_sim", 1.0
    bit, motor = by_stamp(ros, rig)
    with lockstep_rig(ns), \
         NodeProcess("drill_sim_controller", "--ros-args", "-r", f"__ns:={ns}",
                     "-p", f"rig:={rig}", "-p", "inputs:=exact", "-p", "law:=policy",
                     "-p", "policy:=drill_sim.control.policy:proportional_speed_policy",
                     "-p", f"initial_speed_setpoint_rad_s:={61 * RPM!r}"):
        start_when_connected(ros, rig)
        wait_for(lambda: bit and motor and min(max(bit), max(motor)) * 1e-9 >= duration,
                 ros, 240.0, f"{duration} s of lockstep ticks")
    off_bit, off_motor = _policy_offline(proportional_speed_policy, duration)
    n = len(off_bit)
    stamps = sorted(bit)[:n]
    assert stamps == [k * 1_000_000 for k in range(n)]
    ros_bit = np.array([bit[s] for s in stamps])
    ros_motor = np.array([motor[s] for s in stamps])
    assert np.ptp(off_motor) > 30.0                       # the policy acts: not a hold
    assert np.allclose(ros_bit, off_bit, rtol=0.0, atol=1e-9 * math.tau)
    assert np.allclose(ros_motor, off_motor, rtol=1e-12, atol=1e-6)
    # another policy offline is told apart: the comparison can fail
    other_bit, _ = _policy_offline(lambda o: proportional_speed_policy(o) * 1.001, duration)
    assert not np.allclose(ros_bit, other_bit, rtol=0.0, atol=1e-9 * math.tau)
