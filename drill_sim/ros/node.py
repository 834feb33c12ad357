"""``drill_sim_node``: the rig as a ROS 2 node. Surface commands in, bit and surface response out.

A thin binding of a ``RigSession`` (``drill_sim.session``: the rig, its sensors, the command
rules, pause/step/reset, parameter changes, pacing, lockstep, diagnostics, recording) to rclpy:
its endpoints come from the table in ``wire.rig_topics``, commands go into the session, its
bytes out to the publishers. Commands are taken by the tick itself (``commands``: a bounded
number per tick, so a flood of them cannot stop the clock); a refused command never reaches
the model. The loops (real time, max speed, lockstep) are in ``loops``.
"""

from __future__ import annotations

import sys
import time
from collections import deque

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import SetParametersResult
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.serialization import serialize_message
from std_srvs.srv import SetBool, Trigger

from ..core import NoSteadyDrilling, ParameterError
from ..session.diagnostics import CommandCounts, other_publishers_words, shared_command_words
from ..session.recorder import RecordRefused
from ..session.rig_session import Naming, RigSession
from ..wire import rig_topics
from ..wire.rig_topics import RigTopic
from . import loops, parameters
from .command_owner import CommandOwnership
from .commands import CommandInbox
from .controller_switch import switcher
from .publisher_take import PublisherTakeUnavailable
from .stopping import init_stoppable
from .topics import (
    NOT_YET_NAMED,
    message_class,
    publisher_names,
    raw_sender,
    rclpy_qos,
    service_class,
)
from .wakeups import request_cpu_latency, take_thread_priority

SWITCH_INTERVAL_S = 5e-4
# real time: which outputs have a subscriber is looked at this often (a publish to no one
# still costs ~6 us, and there are 16 outputs, 17 with /clock); a new subscriber is served within it
LIVE_REFRESH_PERIOD_S = 0.05


class RigNode(Node):
    """The drilling rig node. Parameters, topics and services: msg_docs/node.md."""

    def __init__(self, **kwargs) -> None:
        super().__init__(rig_topics.NODE_NAME, **kwargs)
        try:
            self.preset, self._specs, p = parameters.declare(self)
            scenario, p = parameters.scenario_of(self, p, self._specs)
            self.session = RigSession(
                p, geometry=self.preset.string, preset=self.preset.name,
                naming=Naming(self.get_fully_qualified_name(), self.resolve_topic_name),
                log=self.get_logger())
        except (ParameterError, NoSteadyDrilling) as exc:
            raise SystemExit(f"drill_sim_node: {exc}") from None
        except RecordRefused as exc:             # it says what is expected
            raise SystemExit(f"drill_sim_node: parameter record = {p['record']!r}: "
                             f"{exc} (nothing was run)") from None
        if scenario is not None:                 # checked above: nothing is refused now
            self.session.play(scenario, switcher(self, p["scenario_controller"])
                              if p["scenario_controller"] else None)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        session = self.session
        # every topic and service from the table, outputs in publishing order
        self._outputs = [self._publisher(t) for t in session.outputs]
        self.send = [raw_sender(p) for p in self._outputs]     # CDR bytes, one call each
        self._next_live_refresh = 0.0
        self._diagnostics = self._publisher(rig_topics.DIAGNOSTICS_TOPIC)
        self._own_diagnostics: deque[bytes] = deque(maxlen=4)   # ours, as published
        if self.session.recorder is not None:
            # what other nodes report (a controller's law, gains, activity) goes into the
            # session's bag beside the rig's own status
            t = rig_topics.DIAGNOSTICS_TOPIC
            self.create_subscription(message_class(t.type_name), t.name,
                                     self._record_others_diagnostics,
                                     rclpy_qos(t.qos_for(self.p["qos_reliability"])), raw=True)
        self._samples_topic = self.resolve_topic_name(rig_topics.JOINT_STATES.name)
        self._others: tuple[str, ...] = ()       # other publishers on it, last looked at
        self._shared: tuple[tuple[str, tuple[str, ...]], ...] = ()   # shared command topics
        owner_first = p["command_owner"] == "first"
        try:
            self.commands = CommandInbox(self, p["qos_reliability"], owner_first=owner_first)
        except PublisherTakeUnavailable as exc:
            raise SystemExit(f"drill_sim_node: parameter command_owner = 'first' needs rcl's "
                             f"take with the publisher's GID: {exc}; use command_owner:=any "
                             "(nothing was run)") from None
        self._ownership = CommandOwnership(self, self.commands) if owner_first else None
        self._undecodable = self._lost_before = 0
        handlers = {"~/reset": self._on_reset, "~/pause": self._on_pause, "~/step": self._on_step}
        for t in rig_topics.SERVICES:
            self.create_service(service_class(t.type_name), t.name, handlers[t.name])
        self.create_timer(p["diagnostics_period_s"], self.publish_diagnostics)
        if session.lockstep is not None:
            pace = "lockstep on " + ", ".join(p["lockstep_topics"])
        else:
            pace = "real-time factor " + ("max" if session.pacer.max_speed
                                          else f"{p['real_time_factor']:g}")
        self.get_logger().info(
            f"rig '{self.preset.name}' ready: {p['string_model']} string, "
            f"t* = {session.rig.scales.time_s:.3f} s, "
            f"dt = {session.rig.dt_s:.4g} s ({session.steps_per_tick} a tick), "
            f"{p['rate_hz']:g} Hz, {pace}, "
            f"{'publishing /clock' if session.with_clock else 'wall-clock stamps'}, sensors "
            f"'{session.sensors.profile.name}' (seed {session.sensors.seed})"
            f"{f', playing scenario {scenario.name!r}' if scenario is not None else ''}"
            f"{', paused' if session.paused else ''}")
        self.get_logger().info(f"rig figures: {session.figures()}")
        parameters.warn_unknown_given(self)

    @property
    def p(self) -> dict[str, object]:
        return self.session.p

    def _publisher(self, t: RigTopic) -> Publisher:
        return self.create_publisher(message_class(t.type_name), t.name,
                                     rclpy_qos(t.qos_for(self.p["qos_reliability"])))

    # ---- the tick ----------------------------------------------------------------------
    def tick(self) -> None:
        """A real-time or max-speed tick: take the commands, advance the ticks due, publish
        (each tick's sample, also the ticks a stall delayed: ``Pacer.samples``)."""
        session = self.session
        pacer = session.pacer
        pacer.tick_started()
        self.take_commands()
        if session.paused:
            return
        for ticks in pacer.samples(pacer.due()):   # after a stall: one by one
            if not session.advance_and_emit(ticks, self.send):
                break
            pacer.advanced(ticks)
        if not pacer.max_speed and (now := time.monotonic()) >= self._next_live_refresh:
            session.set_live([p.get_subscription_count() > 0 for p in self._outputs])
            self._next_live_refresh = now + LIVE_REFRESH_PERIOD_S

    def serve(self, executor: EventsExecutor) -> None:
        """Between back-to-back ticks: services, parameters and diagnostics; and which outputs
        have a subscriber now (the others are neither published, nor encoded unless
        recorded, until they have one: a publish to no one costs ~6 us, an encoding ~5 us)."""
        executor.spin_once(timeout_sec=0.0)
        self.session.set_live([p.get_subscription_count() > 0 for p in self._outputs])

    def lockstep_overdue(self, now: float) -> None:
        """The tick waited ``lockstep_timeout_s``: say for what (at most once a second), and
        publish it again (not recorded again) so a controller that started or restarted late
        can answer it."""
        st = self.session.lockstep.status(now)
        self.get_logger().warning(
            f"lockstep: waiting {st.waiting_s:.1f} s for a command stamped "
            f"{st.stamp_ns * 1e-9:.6f} s on {', '.join(st.missing)}; publishing that tick "
            "again and waiting on (the rig never advances without its controller)",
            throttle_duration_sec=1.0)             # said once a second, however short the timeout
        self.session.emit_again(self.send)     # to every output: subscribers may be new

    # ---- commands ----------------------------------------------------------------------
    def take_commands(self) -> None:
        """The commands that arrived since the last tick, in arrival order, into the session:
        each recorded as received and used only if the session's rule accepts it (frame
        expected, value finite and in range), else the last valid command is held."""
        batch = self.commands.take()
        if self._ownership is not None:
            self._ownership.after_take()
        if self.commands.undecodable != self._undecodable:
            self._undecodable = self.commands.undecodable
            self.get_logger().warning(f"{self._undecodable} command messages could not be "
                                      "decoded and were ignored; the last, on "
                                      f"{self.commands.last_undecodable}",
                                      throttle_duration_sec=1.0)
        if not batch:
            return
        accepted = 0
        topics: set[str] = set()
        command = self.session.commands.command
        for c in batch:
            refusal = command(c.topic, c.frame_id, c.six, c.data, (c.sec, c.nanosec))
            if refusal is None:
                accepted += 1
                topics.add(c.topic.name)
            elif refusal == "in flight":
                self.get_logger().info(f"dropped a {c.topic.name} command sent before the "
                                       "drive left its mode", throttle_duration_sec=1.0)
            else:
                what, value, expected = refusal
                self.get_logger().warning(f"refused {what} = {value!r}: expected {expected}; "
                                          "holding the last valid command",
                                          throttle_duration_sec=1.0)
        self.session.commands.taken(accepted, len(topics))

    # ---- services ----------------------------------------------------------------------
    def _on_reset(self, request: Trigger.Request, response: Trigger.Response):
        response.success, response.message = self.session.reset(self.send)
        return response

    def _on_pause(self, request: SetBool.Request, response: SetBool.Response):
        response.message = self.session.pause(bool(request.data))
        response.success = True
        return response

    def _on_step(self, request: Trigger.Request, response: Trigger.Response):
        response.success, response.message = self.session.step(self.send)
        return response

    # ---- parameters at run time --------------------------------------------------------
    def set_parameters_atomically(self, parameter_list) -> SetParametersResult:
        """What the parameter services call: a parameter that cannot change at run time, or
        a value out of its range, is refused with the reason (rclpy's would not say why)."""
        refusal = parameters.refusal(getattr(self, "_specs", {}), parameter_list)
        if refusal is not None:
            return SetParametersResult(successful=False, reason=refusal)
        return super().set_parameters_atomically(parameter_list)

    def _on_set_parameters(self, params) -> SetParametersResult:
        new, refusal = parameters.changed(self._specs, self.p, params)
        if refusal is not None:
            return SetParametersResult(successful=False, reason=refusal)
        try:
            self.session.change(new)
        except ParameterError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    # ---- diagnostics -------------------------------------------------------------------
    def other_publishers(self) -> tuple[str, ...]:
        """The nodes besides this one that publish on its ``~/joint_states`` (fully qualified
        names; this rig's own name again when a second rig of the same name runs), said in
        the log when they come and go."""
        # an endpoint whose node is not named yet is looked at again next time
        names = sorted(n for n in publisher_names(
            self.get_publishers_info_by_topic(self._samples_topic)) if n != NOT_YET_NAMED)
        if self.get_fully_qualified_name() in names:
            names.remove(self.get_fully_qualified_name())
        others = tuple(names)
        if others != self._others:
            if others:
                self.get_logger().error(other_publishers_words(others))
            else:
                self.get_logger().info(f"{self._samples_topic}: this rig is its only "
                                       "publisher again")
            self._others = others
        return others

    def shared_commands(self, owners: dict[str, str]) -> tuple[tuple[str, tuple[str, ...]], ...]:
        """The command topics that more than one node publishes on now, with the nodes' names;
        said in the log when it starts and when it ends, with the topic's owner (``owners``,
        command_owner first) whose commands alone are taken."""
        shared = []
        for t in rig_topics.COMMANDS:
            names = tuple(sorted(publisher_names(self.get_publishers_info_by_topic(
                self.resolve_topic_name(t.name)))))
            if len(names) > 1:
                shared.append((t.name, names))
        shared_now = tuple(shared)
        if shared_now != self._shared:
            before = dict(self._shared)
            for topic, names in shared_now:
                if before.get(topic) != names:
                    self.get_logger().warning(shared_command_words(topic, names,
                                                                   owners.get(topic)))
            for topic in set(before) - {topic for topic, _ in shared_now}:
                self.get_logger().info(f"{topic}: one publisher again")
            self._shared = shared_now
        return shared_now

    def publish_diagnostics(self) -> None:
        """The session's status (``session.diagnostics.rig_status``) as a DiagnosticArray."""
        session, inbox = self.session, self.commands
        owners = () if self._ownership is None else self._ownership.check_graph()
        status = session.status(other_publishers=self.other_publishers(), commands=CommandCounts(
            inbox.received, session.commands.superseded, inbox.lost,
            inbox.lost - self._lost_before, self.shared_commands(dict(owners)), inbox.refused,
            owners))
        self._lost_before = inbox.lost
        array = DiagnosticArray(status=[DiagnosticStatus(
            level=bytes([status.level]), name=f"{self.get_name()}: rig", message=status.message,
            hardware_id=self.preset.name,
            values=[KeyValue(key=k, value=v) for k, v in status.values.items()])])
        array.header.stamp = self.get_clock().now().to_msg()
        if session.recorder is None:
            self._diagnostics.publish(array)
        else:                                    # serialized once: published and recorded
            data = serialize_message(array)
            self._own_diagnostics.append(data)
            self._diagnostics.publish(data)
            session.recorder.record_diagnostics(data)

    def _record_others_diagnostics(self, data: bytes) -> None:
        """Another node's /diagnostics (ours come back too and are already recorded)."""
        if data not in self._own_diagnostics:
            self.session.recorder.record_diagnostics(data)


def main(args: list[str] | None = None) -> int:
    # SIGINT/SIGTERM only raise a flag, so the node always stops between two ticks: no tick
    # is cut in half (published but not recorded, or recorded in part).
    stop = init_stoppable(args, ros_args_only=True)
    # The recorder's threads (chunk assembly, finishing a split file) run Python too; a tick
    # waiting for the GIL gets it within this switch interval, not Python's default 5 ms.
    sys.setswitchinterval(SWITCH_INTERVAL_S)
    node = executor = latency = None
    try:
        node = RigNode()
        executor = EventsExecutor()
        executor.add_node(node)
        node.session.rig.warm_up()   # load the compiled kernel before the first tick is due
        take_thread_priority(node.p, node.session.pacer.max_speed and node.session.lockstep is None,
                             node.get_logger())
        latency = request_cpu_latency(node.p, node.get_logger())
        # The loops serve the executor (EventsExecutor: a fifth of the CPU of the
        # SingleThreadedExecutor) with spin_once between their ticks.
        loops.run(node, executor, stop)
    except SystemExit as exc:     # a bad parameter at start-up: one clear line
        print(exc, file=sys.stderr)
        return 2
    finally:
        if node is not None:
            print(f"drill_sim_node: shut down at t = {node.session.sim_time_s:.3f} s",
                  file=sys.stderr)
            node.session.close()
            if executor is not None:
                executor.shutdown()
            node.commands.destroy()
            node.destroy_node()
        if latency is not None:
            latency.close()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
