"""The offline loop and the nodes in lockstep are the same loop: the installed rig node (torque
mode, lockstep on its motor-torque command) and drill_sim_controller give, sample by sample, the
bit speed and motor torque ``drill_sim.control.closed_loop.run_loop`` computes in-process for the
same law, gains, sample instants and start (steady at 60 rpm, set-point 61 rpm: a transient
that the law must work through, its integral off the limits)."""

from __future__ import annotations

import math

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


def test_lockstep_nodes_reproduce_the_offline_loop(ros):
    preset = load_preset("base")
    gains = reference_gains("z_torque", preset, 2900.0)
    bit: dict[int, float] = {}
    motor: dict[int, float] = {}

    def stamp(m) -> int:
        return m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec

    ros.create_subscription(TwistStamped, f"{RIG}/bit/twist",
                            lambda m: bit.__setitem__(stamp(m), m.twist.angular.z), 10000)
    ros.create_subscription(WrenchStamped, f"{RIG}/top_drive/motor_wrench",
                            lambda m: motor.__setitem__(stamp(m), m.wrench.torque.z), 10000)
    controller = ["-p", f"rig:={RIG}", "-p", "inputs:=exact",
                  "-p", f"initial_speed_setpoint_rad_s:={61 * RPM!r}",
                  *(a for k, v in gains.items() for a in ("-p", f"z_torque.{k}:={float(v)!r}"))]
    with NodeProcess("drill_sim_node", "--ros-args", "-r", f"__ns:={NS}",
                     "-p", "top_drive_mode:=torque", "-p", "publish_clock:=true",
                     "-p", "lockstep:=true", "-p", "lockstep_topics:=[cmd/top_drive_torque]",
                     "-p", "lockstep_timeout_s:=0.5", "-p", "start_paused:=true"), \
         NodeProcess("drill_sim_controller", "--ros-args", "-r", f"__ns:={NS}", *controller):
        wait_for(lambda: ros.count_publishers(f"{RIG}/cmd/top_drive_torque") > 0
                 and ros.count_subscribers(f"{RIG}/top_drive/motor_wrench") >= 2
                 and ros.count_publishers(f"{RIG}/bit/twist") > 0, ros, 60.0,
                 "the rig and the controller connected")
        assert call_service(ros, SetBool, f"{RIG}/pause", SetBool.Request(data=False)).success
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
    motor: dict[int, float] = {}

    def stamp(m) -> int:
        return m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec

    ros.create_subscription(WrenchStamped, f"{rig}/top_drive/motor_wrench",
                            lambda m: motor.__setitem__(stamp(m), m.wrench.torque.z), 10000)
    with NodeProcess("drill_sim_node", "--ros-args", "-r", f"__ns:={ns}",
                     "-p", "top_drive_mode:=torque", "-p", "publish_clock:=true",
                     "-p", "lockstep:=true", "-p", "lockstep_topics:=[cmd/top_drive_torque]",
                     "-p", "lockstep_timeout_s:=5.0", "-p", "start_paused:=true",
                     "-p", f"record:={bag}"), \
         NodeProcess("drill_sim_controller", "--ros-args", "-r", f"__ns:={ns}",
                     "-p", f"rig:={rig}", "-p", "inputs:=exact", "-p", "enabled:=false"):
        wait_for(lambda: ros.count_publishers(f"{rig}/cmd/top_drive_torque") > 0
                 and ros.count_subscribers(f"{rig}/top_drive/motor_wrench") >= 2, ros, 60.0,
                 "the rig and the controller connected")
        assert call_service(ros, SetBool, f"{rig}/pause", SetBool.Request(data=False)).success
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
    # the answers as the rig took them (its bag records every command it takes; a test's own
    # subscription may miss some on a loaded machine)
    from rclpy.serialization import deserialize_message

    from drill_sim.bag.reader import read_messages
    answers = {}
    for m in read_messages(bag):
        if m.topic == f"{rig}/cmd/top_drive_torque":
            msg = deserialize_message(m.data, WrenchStamped)
            answers[stamp(msg)] = msg.wrench.torque.z
    assert all(t in answers for t in ticks)
    assert np.allclose([answers[t] for t in ticks], motor[0], rtol=1e-12)   # a hold
    assert np.ptp([motor[t] for t in ticks]) < 1e-9 * abs(motor[0]) + 1e-9


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
    bit: dict[int, float] = {}
    motor: dict[int, float] = {}

    def stamp(m) -> int:
        return m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec

    ros.create_subscription(TwistStamped, f"{rig}/bit/twist",
                            lambda m: bit.__setitem__(stamp(m), m.twist.angular.z), 10000)
    ros.create_subscription(WrenchStamped, f"{rig}/top_drive/motor_wrench",
                            lambda m: motor.__setitem__(stamp(m), m.wrench.torque.z), 10000)
    with NodeProcess("drill_sim_node", "--ros-args", "-r", f"__ns:={ns}",
                     "-p", "top_drive_mode:=torque", "-p", "publish_clock:=true",
                     "-p", "lockstep:=true", "-p", "lockstep_topics:=[cmd/top_drive_torque]",
                     "-p", "lockstep_timeout_s:=0.5", "-p", "start_paused:=true"), \
         NodeProcess("drill_sim_controller", "--ros-args", "-r", f"__ns:={ns}",
                     "-p", f"rig:={rig}", "-p", "inputs:=exact", "-p", "law:=policy",
                     "-p", "policy:=drill_sim.control.policy:proportional_speed_policy",
                     "-p", f"initial_speed_setpoint_rad_s:={61 * RPM!r}"):
        wait_for(lambda: ros.count_publishers(f"{rig}/cmd/top_drive_torque") > 0
                 and ros.count_subscribers(f"{rig}/top_drive/motor_wrench") >= 2
                 and ros.count_publishers(f"{rig}/bit/twist") > 0, ros, 60.0,
                 "the rig and the controller connected")
        assert call_service(ros, SetBool, f"{rig}/pause", SetBool.Request(data=False)).success
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
