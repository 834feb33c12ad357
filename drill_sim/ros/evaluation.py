"""``drill_sim control --ros``: one scenario scored through the nodes, in lockstep.

The installed rig node (torque mode, ``publish_clock``, ``lockstep`` on the motor-torque
command, started paused) and a controller — ``drill_sim_controller`` with the law's gains, or
any command line that speaks the rig's topics — run in subprocesses in their own namespace; this
process records the rig's exact outputs at every tick, releases the pause once everyone is
connected and stops after the scenario's duration. The kinematic row has no controller: this
process answers each tick with the speed set-point.

Set-points that change (a WOB step, a speed ramp) are played by this process in the lockstep:
on tick k (stamp k·h) it sends the hook load for the interval after it, stamped k·h, on the
rig's ``cmd/hook_load`` (a lockstep topic, so the rig waits for it as for the torque) and the
speed set-point of sample k, stamped k·h, to the controller, which with ``setpoint_lockstep``
waits for it and applies it before stepping sample k. These are the offline loop's instants
(``run_loop``: set-point k at sample k, hook load k held over k..k+1), so both loops agree to
round-off whatever the wall-clock order of the messages. A switch-on runs the controller with
``stiff_pi`` (the offline loop's drive loop) until then; on the switch-on tick this process
sets the controller's ``law`` and only once that is done sends the tick's set-point, so the
law takes over (bumplessly) at exactly that sample, as offline.
"""

from __future__ import annotations

import os
import shlex
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from ..control import LAWS, closed_loop
from ..control.evaluation import LoopSettings, Scenario, law_top_drive
from ..control.tuning import pipe_impedance
from ..core import Preset
from ..core.parameters import ParameterError
from ..core.rig_sample import REGIME_STUCK
from ..programs import program
from ..session.parameter_table import specs
from ..wire.rig_topics import JOINT_PLACES, topic

NS = "/drill_sim_control"
RIG = f"{NS}/drill_sim"
SETPOINT = f"{NS}/speed_setpoint"        # this process's stamped set-points to the controller


def at_rig(name: str) -> str:
    """The full name of the rig's topic or service ``name`` (``~/...``, from the topics table)."""
    return topic(name).under(RIG)

SERIES = ("bit_speed_rad_s", "stuck", "surface_torque_nm", "motor_torque_nm", "bit_depth_m",
          "top_drive_angle_rad", "wob_n", "top_drive_speed_rad_s")


def check_ros(scenario: Scenario, *, user_command: str | None = None) -> None:
    """ParameterError for a scenario the nodes cannot play with a user's controller: it is
    given no set-point and no switch-on, so its scenario's speed must be constant and its law
    on from the start."""
    if user_command and scenario.switch_on_s > 0.0:
        raise ParameterError(f"scenario {scenario.name!r}: a --ros-controller cannot be "
                             "switched on: expected a scenario with the law from the start")
    if user_command and not scenario.speed_is_constant:
        raise ParameterError(f"scenario {scenario.name!r}: a --ros-controller gets no stamped "
                             "set-point: expected a constant rpm")


def tick_commands(preset: Preset, scenario: Scenario, settings: LoopSettings
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(speed set-point [rad/s], hook load [N]) at each tick k·h, as ``run_loop`` computes
    them (``closed_loop.tick_commands``), so the nodes get the very numbers the offline loop
    uses."""
    check_ros(scenario)
    return closed_loop.tick_commands(preset, scenario, settings.sample_period_s)


def ros_value(value: object) -> str:
    """A parameter value as ``-p name:=VALUE`` takes it."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(ros_value(v) for v in value) + "]"
    return str(value)


def rig_command(preset: Preset, scenario: Scenario, settings: LoopSettings) -> list[str]:
    """The rig node of the offline loop's session (``closed_loop.session_parameters``: the
    same drive, start, sensors and string), paused, in lockstep on the loop's commands."""
    check_ros(scenario)
    p = closed_loop.session_parameters(preset, scenario, settings)
    defaults = {s.name: s.default for s in specs(preset)}
    given = {k: v for k, v in p.items()
             if k not in ("max_speed", "record") and v != defaults.get(k)}
    topic = LAWS[settings.law].command_topic.removeprefix("~/")
    given.update(preset=preset.name, lockstep=True, lockstep_topics=[topic, "cmd/hook_load"],
                 start_paused=True, lockstep_timeout_s=3600.0)
    cmd = [program("drill_sim_node"), "--ros-args", "-r", f"__ns:={NS}"]
    for k, v in given.items():
        cmd += ["-p", f"{k}:={ros_value(v)}"]
    return cmd


def controller_command(preset: Preset, scenario: Scenario, settings: LoopSettings,
                       user_command: str | None) -> list[str] | None:
    """Our controller with the law's gains, the user's command (namespaced with the rig), or
    None for the kinematic row."""
    if user_command:
        return [*shlex.split(user_command), "--ros-args", "-r", f"__ns:={NS}"]
    if LAWS[settings.law].output_kind == "speed":        # the set-point goes to the rig
        return None
    speed_set, _ = tick_commands(preset, scenario, settings)
    drive = law_top_drive(preset, settings.law, settings.top_drive)
    first = "stiff_pi" if scenario.switch_on_s > 0.0 else settings.law   # the drive's loop
    params = {"rig": RIG, "law": first, "inputs": "measured",
              "sample_period_s": repr(settings.sample_period_s),
              "impedance_nm_s_rad": repr(pipe_impedance(preset)),
              "top_drive_inertia_kg_m2": repr(drive.top_drive_inertia_kg_m2),
              "initial_speed_setpoint_rad_s": repr(float(speed_set[0])),
              "setpoint_topic": SETPOINT, "setpoint_lockstep": "true",
              f"{settings.law}.torque_min_nm": repr(drive.motor_torque_min_nm),
              f"{settings.law}.torque_max_nm": repr(drive.motor_torque_max_nm),
              "stiff_pi.torque_min_nm": repr(drive.motor_torque_min_nm),
              "stiff_pi.torque_max_nm": repr(drive.motor_torque_max_nm)}
    params.update({f"{settings.law}.{k}": repr(float(v)) for k, v in settings.gains.items()})
    cmd = [program("drill_sim_controller"), "--ros-args", "-r", f"__ns:={NS}"]
    for k, v in params.items():
        cmd += ["-p", f"{k}:={v}"]
    return cmd


def run_ros(preset: Preset, scenario: Scenario, settings: LoopSettings, *,
            user_command: str | None = None, timeout_s: float = 3600.0,
            progress=None) -> dict[str, np.ndarray]:
    """The rig's series at every tick up to the scenario's duration (keys: ``time_s`` and
    SERIES), through the nodes in lockstep."""
    import rclpy
    from geometry_msgs.msg import TwistStamped, WrenchStamped
    from rcl_interfaces.msg import Parameter as ParameterMsg
    from rcl_interfaces.msg import ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters
    from sensor_msgs.msg import JointState
    from std_msgs.msg import UInt8
    from std_srvs.srv import SetBool

    from .stopping import stop_processes

    check_ros(scenario, user_command=user_command)
    speed_set, hook = tick_commands(preset, scenario, settings)
    n = len(speed_set)
    ns_per_tick = round(settings.sample_period_s * 1e9)
    data: dict[str, dict[int, float]] = {k: {} for k in SERIES}
    owns = not rclpy.ok()
    if owns:
        rclpy.init()
    node = rclpy.create_node("drill_sim_control_harness")
    depth, depth_out = 10000, 100
    procs: list[subprocess.Popen] = []

    def stamp(m) -> int:
        return m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec

    def put(key: str, m, value: float) -> None:
        data[key][stamp(m)] = value

    kinematic = LAWS[settings.law].output_kind == "speed"
    speed_pub = node.create_publisher(
        TwistStamped, at_rig("~/cmd/top_drive") if kinematic else SETPOINT, depth_out)
    hook_pub = node.create_publisher(WrenchStamped, at_rig("~/cmd/hook_load"), depth_out)
    answer = TwistStamped()
    answer.header.frame_id = "top_drive"
    load = WrenchStamped()
    load.header.frame_id = "top_drive"

    # the switch-on sample (offline: ceil(switch_on_s / h)); the kinematic row has none
    switch_k = None if kinematic or scenario.switch_on_s <= 0.0 else \
        scenario.switch_on_sample(settings.sample_period_s)
    switcher = node.create_client(SetParameters, f"{NS}/drill_sim_controller/set_parameters")
    switched: list[bool] = []                  # the controller's answer to the switch
    switching: list[int] = []                  # the switch was asked for

    def switch_then_publish(setpoint: TwistStamped) -> None:
        """The law on, then the switch-on sample's set-point: the controller waits for that
        set-point, so the new law steps first on that very sample."""
        value = ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=settings.law)
        future = switcher.call_async(SetParameters.Request(
            parameters=[ParameterMsg(name="law", value=value)]))

        def done(f) -> None:
            result = f.result()
            if result is None or not result.results or not result.results[0].successful:
                switched.append(False)
                return
            switched.append(True)
            speed_pub.publish(setpoint)
        future.add_done_callback(done)

    def on_bit(m) -> None:
        """Tick k: the set-point of sample k (the kinematic row's speed command, else the
        controller's set-point) and the hook load held over k..k+1, both stamped k·h."""
        put("bit_speed_rad_s", m, m.twist.angular.z)
        k = min(round(stamp(m) / ns_per_tick), n - 1)
        answer.header.stamp = load.header.stamp = m.header.stamp
        answer.twist.angular.z = float(speed_set[k])
        load.wrench.force.z = float(hook[k])
        hook_pub.publish(load)
        if k == switch_k:                        # once, even if the rig repeats the tick
            if not switching:
                switching.append(k)
                later = TwistStamped()
                later.header.frame_id = answer.header.frame_id
                later.header.stamp = m.header.stamp
                later.twist.angular.z = float(speed_set[k])
                switch_then_publish(later)
            return
        speed_pub.publish(answer)

    node.create_subscription(TwistStamped, at_rig("~/bit/twist"), on_bit, depth)
    node.create_subscription(UInt8, at_rig("~/bit/regime"), lambda m: data["stuck"].__setitem__(
        len(data["stuck"]), float(m.data == REGIME_STUCK)), depth)
    node.create_subscription(WrenchStamped, at_rig("~/top_drive/wrench"), lambda m: put(
        "surface_torque_nm", m, m.wrench.torque.z), depth)
    node.create_subscription(WrenchStamped, at_rig("~/top_drive/motor_wrench"), lambda m: put(
        "motor_torque_nm", m, m.wrench.torque.z), depth)
    node.create_subscription(WrenchStamped, at_rig("~/bit/wrench"), lambda m: put(
        "wob_n", m, m.wrench.force.z), depth)

    def on_joints(m) -> None:
        for name in ("bit_depth_m", "top_drive_angle_rad", "top_drive_speed_rad_s"):
            array, j = JOINT_PLACES[name]
            put(name, m, getattr(m, array)[j])
    node.create_subscription(JointState, at_rig("~/joint_states"), on_joints, depth)
    env = dict(os.environ)
    # the rig's log goes to a file, not a pipe: a pipe nobody reads fills up and blocks the rig
    rig_log = tempfile.TemporaryFile(mode="w+")
    try:
        procs.append(subprocess.Popen(rig_command(preset, scenario, settings), env=env,
                                      stdout=subprocess.DEVNULL, stderr=rig_log, text=True))
        ctl = controller_command(preset, scenario, settings, user_command)
        if ctl is not None:
            procs.append(subprocess.Popen(ctl, env=env, stdout=subprocess.DEVNULL))
        cmd_topic = at_rig("~/cmd/top_drive") if ctl is None else at_rig("~/cmd/top_drive_torque")
        pause = node.create_client(SetBool, at_rig("~/pause"))
        end = time.monotonic() + 60.0
        while not (pause.service_is_ready() and node.count_publishers(cmd_topic) > 0
                   and hook_pub.get_subscription_count() > 0
                   and (ctl is None or user_command or speed_pub.get_subscription_count() > 0)
                   and (switch_k is None or switcher.service_is_ready())
                   and node.count_publishers(at_rig("~/joint_states")) > 0
                   and (ctl is None or node.count_subscribers(
                       at_rig("~/measured/top_drive/motor_wrench")) > 0)):
            _check_alive(procs, rig_log)
            if time.monotonic() > end:
                raise OSError("the rig and the controller did not connect within 60 s")
            rclpy.spin_once(node, timeout_sec=0.05)
        time.sleep(2.0)                         # let the subscriptions match both ways (a
        # loaded machine took longer than 0.5 s: the first tick's sample was missed and the
        # lockstep waited for an answer that never came)
        future = pause.call_async(SetBool.Request(data=False))
        end = time.monotonic() + timeout_s
        last = -1
        while min(len(v) for v in data.values()) < n:
            rclpy.spin_once(node, timeout_sec=0.05)
            _check_alive(procs, rig_log)
            if switched and not switched[0]:
                raise OSError(f"the controller refused law = {settings.law} at switch-on")
            if time.monotonic() > end:
                stop_processes(procs)
                raise OSError(f"lockstep run stalled: {min(len(v) for v in data.values())} of "
                              f"{n} ticks after {timeout_s:g} s; the rig's log ended: "
                              + " | ".join(_tail(rig_log, 5)))
            got = len(data["bit_speed_rad_s"])
            if progress is not None and got != last:
                last = got
                progress(min(got / n, 1.0))
        del future
    finally:
        stop_processes(procs)
        rig_log.close()
        node.destroy_node()
        if owns:
            rclpy.try_shutdown()
    stamps = sorted(data["bit_speed_rad_s"])[:n]
    out = {"time_s": np.array(stamps, dtype=float) * 1e-9}
    for k in SERIES:
        if k == "stuck":
            out[k] = np.array([data[k][i] for i in range(n)])
        else:
            out[k] = np.array([data[k][s] for s in stamps])
    return out


def _tail(log, lines: int) -> list[str]:
    """The last ``lines`` non-empty lines written to the file ``log``."""
    log.flush()
    log.seek(0)
    return [line for line in log.read().splitlines() if line.strip()][-lines:] or ["(empty)"]


def _check_alive(procs: list[subprocess.Popen], rig_log) -> None:
    """Raise naming the first program that stopped (the rig with its log's last line)."""
    for i, p in enumerate(procs):
        if p.poll() is not None:
            said = f": {_tail(rig_log, 1)[0]}" if i == 0 else ""
            raise OSError(f"{Path(p.args[0]).name} stopped with status {p.returncode}{said}")
