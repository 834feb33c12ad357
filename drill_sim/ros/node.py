"""``drill_sim_node``: the rig as a ROS 2 node. Surface commands in, bit and surface response out.

A thin adapter: each tick advances the core ``Rig`` by the whole ticks of 1/``rate_hz`` the
``Pacer`` gives and publishes its sample, encoded once (``wire.rig_messages``). Topics and
services come from the table in ``wire.rig_topics``; the rules live in ``core``: commands and
parameter changes in ``session``, pacing in ``pacing``, the diagnostics policy in
``diagnostics``, the lockstep wait in ``lockstep``; recording in ``recorder``. Commands are
taken by the tick itself (``commands``: a bounded number per tick, so a flood of them cannot
stop the clock), validated and held (zero-order hold) from that tick on; a refused command
never reaches the model. In lockstep the loop waits, blocked in the middleware, for each
tick's commands before it advances.
"""

from __future__ import annotations

import sys
import time

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import SetParametersResult
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.serialization import serialize_message
from std_srvs.srv import SetBool, Trigger

from ..core import NoSteadyDrilling, ParameterError, session
from ..core.diagnostics import CommandCounts, other_publishers_words, rig_status
from ..core.lockstep import Lockstep
from ..core.pacing import Pacer
from ..core.rig import RigSample
from ..core.sensor_profile import CHANNELS
from ..core.sensors import Measured, session_sensors
from ..wire import rig_topics
from ..wire.rig_messages import RigEncoders
from ..wire.rig_topics import RigTopic
from . import parameters
from .commands import CommandInbox
from .recorder import RecordRefused, SessionRecorder
from .stopping import init_stoppable
from .topics import (
    NOT_YET_NAMED,
    message_class,
    publisher_names,
    raw_sender,
    rclpy_qos,
    service_class,
)
from .wakeups import CpuLatencyRequest, run_at_priority

SWITCH_INTERVAL_S = 5e-4
SERVE_PERIOD_S = 1e-3        # max speed: services, parameters, diagnostics served this often
# real time: served this often [s]. The ticks are paced by the node's own sleep, not by an
# executor timer: dispatching a 1 kHz timer through the executor cost ~7 % of a core more.
REAL_TIME_SERVE_PERIOD_S = 5e-3
# lockstep: served this often [s] (a spin of the executor costs ~0.1 ms, a third of a tick)
LOCKSTEP_SERVE_PERIOD_S = 0.02
# real time: which outputs have a subscriber is looked at this often (a publish to no one
# still costs ~6 us, and there are 16 outputs, 17 with /clock); a new subscriber is served within it
LIVE_REFRESH_PERIOD_S = 0.05
# a command for the top-drive mode the drive left this recently [s] was in flight at the switch
IN_FLIGHT_S = 0.5


class RigNode(Node):
    """The drilling rig node. Parameters, topics and services: msg_docs/node.md."""

    def __init__(self, **kwargs) -> None:
        super().__init__(rig_topics.NODE_NAME, **kwargs)
        try:
            self.preset, self._specs, self.p = parameters.declare(self)
            self.rig = session.make_rig(self.p, geometry=self.preset.string)
            session.start(self.rig, self.p)
            self.sensors = session_sensors(self.p, self.rig.dt_s)   # what ~/measured/ shows
            self.sensors.warm_up()
        except (ParameterError, NoSteadyDrilling) as exc:
            raise SystemExit(f"drill_sim_node: {exc}") from None
        self.add_on_set_parameters_callback(self._on_set_parameters)

        # every topic and service from the table, outputs in publishing order
        self.with_clock = bool(self.p["publish_clock"])
        self._enc = RigEncoders(self.with_clock)
        self._outputs = [self._publisher(t) for t in self._enc.topics]
        self._send = [raw_sender(p) for p in self._outputs]     # CDR bytes, one call each
        self._set_live([True] * len(self._outputs))  # then only the outputs with a subscriber
        # each ~/measured/ output's channels (indices into the sensors' CHANNELS)
        self._channels_of = [(k, tuple(CHANNELS.index(f.sample) for f in t.fields))
                             for k, t in enumerate(self._enc.topics) if self._enc.measured[k]]
        self._on_sample = self.p["measured_publish"] == "on_sample"
        self._next_live_refresh = 0.0
        self._diagnostics = self._publisher(rig_topics.DIAGNOSTICS_TOPIC)
        self._samples_topic = self.resolve_topic_name(rig_topics.JOINT_STATES.name)
        self._others: tuple[str, ...] = ()       # other publishers on it, last looked at
        self.commands = CommandInbox(self, self.p["qos_reliability"])
        self.superseded = 0                      # commands replaced within their tick
        self._mode_left: tuple[str, float] | None = None    # top-drive mode left, wall time
        self._undecodable = self._lost_before = 0
        handlers = {"~/reset": self._on_reset, "~/pause": self._on_pause, "~/step": self._on_step}
        for t in rig_topics.SERVICES:
            self.create_service(service_class(t.type_name), t.name, handlers[t.name])

        self._offset_s = 0.0                     # simulated time before the last reset
        self.paused = bool(self.p["start_paused"])
        self._steps_per_tick = self._tick_steps(self.p["rate_hz"])
        self._last: tuple | None = None           # the last sample: stamp, sample, measured
        self.lockstep = Lockstep(tuple("~/" + n for n in self.p["lockstep_topics"]),
                                 self.p["lockstep_timeout_s"]) if self.p["lockstep"] else None
        self._epoch_ns = time.time_ns()          # stamps = epoch + sim time without /clock
        try:
            self.recorder = SessionRecorder(
                p=self.p, rig=self.rig, preset=self.preset.name,
                node=self.get_fully_qualified_name(), resolve=self.resolve_topic_name,
                stamp_epoch_ns=0 if self.with_clock else self._epoch_ns, logger=self.get_logger(),
                sensors=self.sensors.profile) if self.p["record"] else None
        except RecordRefused as exc:             # it says what is expected
            raise SystemExit(f"drill_sim_node: parameter record = {self.p['record']!r}: "
                             f"{exc} (nothing was run)") from None
        self.pacer = Pacer(self.p["rate_hz"], self.p["real_time_factor"],
                           self._back_to_back(self.p), self.p["diagnostics_period_s"],
                           self.rig.time_s)
        self._cmd_wall = time.monotonic()
        self.create_timer(self.p["diagnostics_period_s"], self.publish_diagnostics)
        self.get_logger().info(
            f"rig '{self.preset.name}' ready: t* = {self.rig.scales.time_s:.3f} s, "
            f"dt = {self.rig.dt_s:.4g} s ({self._steps_per_tick} a tick), {self.p['rate_hz']:g} "
            f"Hz, {self._pace_words()}, "
            f"{'publishing /clock' if self.with_clock else 'wall-clock stamps'}, sensors "
            f"'{self.sensors.profile.name}' (seed {self.sensors.seed})"
            f"{', paused' if self.paused else ''}")
        self.get_logger().info(f"rig figures: {session.figures_line(self.rig.params)}")
        parameters.warn_unknown_given(self)

    def _pace_words(self) -> str:
        if self.lockstep is not None:
            return "lockstep on " + ", ".join(self.p["lockstep_topics"])
        return "real-time factor " + ("max" if self.pacer.max_speed
                                      else f"{self.p['real_time_factor']:g}")

    @staticmethod
    def _back_to_back(p: dict) -> bool:
        """Ticks back to back, one tick each (max speed, lockstep), not paced by the clock."""
        return bool(p["max_speed"]) or bool(p["lockstep"])

    def _tick_steps(self, rate_hz: float) -> int:
        """Steps of the session's step in one tick of 1/``rate_hz`` (a whole number)."""
        return round(1.0 / (rate_hz * self.rig.dt_s))

    def _publisher(self, t: RigTopic) -> Publisher:
        return self.create_publisher(message_class(t.type_name), t.name,
                                     rclpy_qos(t.qos_for(self.p["qos_reliability"])))


    # ---- time --------------------------------------------------------------------------
    @property
    def sim_time_s(self) -> float:
        """Simulated time since the node started [s]; it keeps running across resets."""
        return self._offset_s + self.rig.time_s

    def stamp_ns(self) -> int:
        sim_ns = round(self.sim_time_s * 1e9)
        return sim_ns if self.with_clock else self._epoch_ns + sim_ns

    # ---- the tick ----------------------------------------------------------------------
    def tick(self) -> None:
        """A real-time tick (``run_real_time``) or a max-speed tick: take the commands, advance
        the ticks due, publish (each tick's sample, also the ticks a stall delayed:
        ``Pacer.samples``)."""
        self.pacer.tick_started()
        self.take_commands()
        if self.paused:
            return
        for ticks in self.pacer.samples(self.pacer.due()):   # after a stall: one by one
            if not self.advance(ticks):
                break
            self.pacer.advanced(ticks)
            self.publish_sample(self.rig.sample())
        if not self.pacer.max_speed and (now := time.monotonic()) >= self._next_live_refresh:
            self._set_live([p.get_subscription_count() > 0 for p in self._outputs])
            self._next_live_refresh = now + LIVE_REFRESH_PERIOD_S

    def advance(self, ticks: int) -> bool:
        """Advance the rig by exactly ``ticks`` ticks of 1/``rate_hz``; False (and paused) if
        the model refuses a step."""
        try:
            self.rig.advance_steps(ticks * self._steps_per_tick)
        except ParameterError as exc:   # a step the model refuses: hold the state, say why
            self.paused = True
            self.get_logger().error(f"simulation paused: {exc}; change the commands or "
                                    "parameters, then resume with ~/pause false or ~/reset")
            return False
        return True

    def publish_sample(self, s: RigSample) -> None:
        """Measure the sample, encode both once; publish those bytes and record the very same
        bytes (only the outputs with a subscriber are published; not recording, only they are
        encoded).
        In lockstep the rig then waits for this tick's commands.

        Not recording, the exact outputs are published before the sensors measure (every
        tick: their state goes on whether or not anyone listens), then the measured ones:
        the same order (the table lists ``~/measured/`` last), but a lockstep controller that
        reads exact outputs gets them ~15 us sooner and works while the node measures."""
        stamp = self.stamp_ns()
        send, enc = self._send, self._enc
        if self.recorder is None:
            at = self._live_exact_at
            for k, raw in zip(at, enc.some(stamp, s, None, at), strict=True):
                send[k](raw)
            self._last = (stamp, s, self.sensors.measure(self.rig.time_s, s))
            if self._on_sample and (held := self._held(self._last[2])):
                at = [k for k in self._live_measured_at if k not in held]
            else:
                at = self._live_measured_at
            if at:
                for k, raw in zip(at, enc.some(*self._last, at), strict=True):
                    send[k](raw)
        else:
            self._last = (stamp, s, self.sensors.measure(self.rig.time_s, s))
            data = enc.sample(*self._last)
            held = self._held(self._last[2]) if self._on_sample else ()
            for k in self._live_at:
                if k not in held:
                    send[k](data[k])
            self.recorder.record_outputs(data, held)
        if self.lockstep is not None:
            self.lockstep.wait_for(stamp, time.monotonic())

    def _held(self, m: Measured) -> tuple[int, ...]:
        """The ``~/measured/`` outputs (indices) none of whose channels took a fresh value
        in this reading: with ``measured_publish:=on_sample`` they are neither published nor
        recorded this tick."""
        fresh = m.fresh
        return tuple(k for k, channels in self._channels_of if not any(fresh[c] for c in channels))

    def serve(self, executor: EventsExecutor) -> None:
        """Between back-to-back ticks: services, parameters and diagnostics; and which outputs
        have a subscriber now (the others are neither published, nor encoded unless
        recorded, until they have one: a publish to no one costs ~6 us, an encoding ~5 us, and
        there are 16 outputs, 17 with /clock)."""
        executor.spin_once(timeout_sec=0.0)
        self._set_live([p.get_subscription_count() > 0 for p in self._outputs])

    def _set_live(self, live: list[bool]) -> None:
        """Which outputs are published (and, not recording, encoded); their places, exact
        and measured apart (``publish_sample``)."""
        measured = self._enc.measured
        self._live_at = [k for k, on in enumerate(live) if on]
        self._live_exact_at = [k for k in self._live_at if not measured[k]]
        self._live_measured_at = [k for k in self._live_at if measured[k]]

    def take_thread_priority(self) -> None:
        """``thread_priority`` > 0: this (the loop's) thread under SCHED_FIFO, in real time
        and lockstep; not at max speed, whose loop never sleeps and would starve the machine's
        other programs. Refused, the rig runs on and says why."""
        priority = int(self.p["thread_priority"])
        if not priority:
            return
        if self.pacer.max_speed and self.lockstep is None:
            self.get_logger().info(f"thread_priority {priority} not taken at max speed (its "
                                   "loop never sleeps: under SCHED_FIFO it would starve the "
                                   "machine's other programs)")
            return
        refused = run_at_priority(priority)
        if refused is None:
            self.get_logger().info(f"ticking under SCHED_FIFO, priority {priority}")
        else:
            self.get_logger().warning(f"thread_priority {priority} not taken: {refused}; "
                                      "ticking under the default scheduler")

    def request_cpu_latency(self) -> CpuLatencyRequest | None:
        """``cpu_wakeup_latency_us`` >= 0: the request held open for the node's life (closed
        at shutdown, or by the kernel if the process dies). Refused, the rig runs on and
        says why."""
        latency_us = int(self.p["cpu_wakeup_latency_us"])
        if latency_us < 0:
            return None
        request = CpuLatencyRequest(latency_us)
        if request.held:
            self.get_logger().info(f"idle cores held to wake-ups of at most {latency_us} us "
                                   "while the node runs (the whole machine's setting)")
        else:
            self.get_logger().warning(f"cpu_wakeup_latency_us {latency_us} not taken: "
                                      f"{request.refused}; idle cores sleep as the machine "
                                      "sets")
        return request

    # ---- real time ---------------------------------------------------------------------
    def run_real_time(self, executor: EventsExecutor, stop) -> None:
        """A tick when the pacer says the next is due (``Pacer.next_tick_s``: at factor 1
        every 1/``rate_hz`` of wall time, in phase with its grid, so each wake-up advances
        one tick and a late one costs no simulated time), sleeping in between; paused, a
        tick (commands taken) every 1/``rate_hz``; services, parameters and the diagnostics
        timer are served every REAL_TIME_SERVE_PERIOD_S."""
        next_tick = next_serve = time.monotonic()
        while not stop:
            now = time.monotonic()
            if now >= next_tick:
                self.tick()
                next_tick = (now + 1.0 / self.pacer.rate_hz if self.paused
                             else self.pacer.next_tick_s())
            if now >= next_serve:
                executor.spin_once(timeout_sec=0.0)
                next_serve = now + REAL_TIME_SERVE_PERIOD_S
            pause = min(next_tick, next_serve) - time.monotonic()
            if pause > 0.0:
                time.sleep(pause)

    # ---- lockstep ----------------------------------------------------------------------
    def run_lockstep(self, executor: EventsExecutor, stop) -> None:
        """Publish a tick, wait for a command stamped with its time on every lockstep topic
        (blocked in the middleware: no CPU spent), advance one tick, and so on; services,
        parameters and diagnostics are served every LOCKSTEP_SERVE_PERIOD_S and while paused.

        Per tick one wait, then one take (right after publishing nothing can have answered
        yet), and the wait watches only the lockstep topics: with Fast DDS a wait costs ~25 us
        of CPU plus ~3 us per topic watched, and only lockstep topics release a tick. Other
        commands are still taken with each tick's; while the rig waits they are taken at the
        latest every LOCKSTEP_SERVE_PERIOD_S."""
        ls = self.lockstep
        self.commands.wait_on(ls.topics)
        next_serve = 0.0
        while not stop:
            if self.paused:
                executor.spin_once(timeout_sec=SERVE_PERIOD_S)
                self.take_commands()             # still taken and held while paused
                next_serve = 0.0
                continue
            if ls.stamp_ns is None:              # tick 0, once running
                self.publish_sample(self.rig.sample())
            self.take_commands()
            now = time.monotonic()
            if ls.complete:
                self.pacer.tick_started()        # the periods: wall time per lockstep tick
                if self.advance(1):
                    self.pacer.advanced(1)
                    self.publish_sample(self.rig.sample())
            if not ls.complete and not self.paused:
                if ls.overdue(now):
                    self._lockstep_overdue(now)
                self.commands.wait(min(max(next_serve - now, 0.0), ls.until_overdue(now)))
            if now >= next_serve:
                self.serve(executor)
                next_serve = now + LOCKSTEP_SERVE_PERIOD_S

    def _lockstep_overdue(self, now: float) -> None:
        """The tick waited ``lockstep_timeout_s``: say for what, and publish it again (not
        recorded again) so a controller that started or restarted late can answer it."""
        st = self.lockstep.status(now)
        self.get_logger().warning(
            f"lockstep: waiting {st.waiting_s:.1f} s for a command stamped "
            f"{st.stamp_ns * 1e-9:.6f} s on {', '.join(st.missing)}; publishing that tick "
            "again and waiting on (the rig never advances without its controller)")
        for send, raw in zip(self._send, self._enc.sample(*self._last), strict=True):
            send(raw)                            # to every output: subscribers may be new

    # ---- commands ----------------------------------------------------------------------
    def take_commands(self) -> None:
        """The commands that arrived since the last tick, in arrival order: each recorded as
        received and used only if the session's rule accepts it (frame expected, value finite
        and in range), else the last valid command is held."""
        batch = self.commands.take()
        if self.commands.undecodable != self._undecodable:
            self._undecodable = self.commands.undecodable
            self.get_logger().warning(f"{self._undecodable} command messages could not be "
                                      "decoded (not little-endian CDR?) and were ignored",
                                      throttle_duration_sec=1.0)
        if not batch:
            return
        accepted = 0
        topics: set[str] = set()
        recorder, ls, rig, p = self.recorder, self.lockstep, self.rig, self.p
        for c in batch:
            if recorder is not None:
                recorder.record_command(c.topic, c.data, c.sec, c.nanosec)
            if ls is not None:
                ls.offer(c.topic.name, c.sec * 1_000_000_000 + c.nanosec)
            refusal = session.apply_command(rig, p, c.topic.command, c.frame_id, c.six)
            if refusal is None:
                accepted += 1
                topics.add(c.topic.name)
            elif self._in_flight(c.topic):
                self.get_logger().info(f"dropped a {c.topic.name} command sent before the "
                                       "drive left its mode", throttle_duration_sec=1.0)
            else:
                what, value, expected = refusal
                self.get_logger().warning(f"refused {what} = {value!r}: expected {expected}; "
                                          "holding the last valid command",
                                          throttle_duration_sec=1.0)
        if accepted:
            self._cmd_wall = time.monotonic()
            self.superseded += accepted - len(topics)

    def _in_flight(self, topic: RigTopic) -> bool:
        """A command for the top-drive mode the drive left less than IN_FLIGHT_S ago: sent
        before the switch, it crossed it on the way (a controller handing the drive back), so
        it is dropped without a warning (and recorded; ``bag resim`` drops it too)."""
        left = self._mode_left
        if left is None or time.monotonic() - left[1] > IN_FLIGHT_S:
            return False
        rule = session.COMMANDS.get(topic.command)
        return rule is not None and rule.mode == left[0]

    # ---- services ----------------------------------------------------------------------
    def _on_reset(self, request: Trigger.Request, response: Trigger.Response):
        offset = self._offset_s + self.rig.time_s
        try:
            session.start(self.rig, self.p)
        except (ParameterError, NoSteadyDrilling) as exc:
            response.success, response.message = False, str(exc)
            return response
        if self.recorder is not None:
            self.recorder.record_event("reset", self.sim_time_s)
        self._offset_s = offset
        self.sensors.reset()
        self.pacer.reset(self.rig.time_s)
        self.publish_sample(self.rig.sample())
        response.success = True
        response.message = f"reset to the initial state ({self.p['initial_state']})"
        return response

    def _on_pause(self, request: SetBool.Request, response: SetBool.Response):
        if self.paused and not request.data:
            self.pacer.anchor()
        self.paused = bool(request.data)
        response.success = True
        response.message = "paused" if self.paused else "running"
        return response

    def _on_step(self, request: Trigger.Request, response: Trigger.Response):
        if not self.paused:
            response.success, response.message = False, "step works only while paused"
            return response
        if not self.advance(1):
            response.success, response.message = False, "the model refused the step"
            return response
        self.publish_sample(self.rig.sample())
        response.success = True
        response.message = f"stepped to t = {self.sim_time_s:.6f} s"
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
            changed = session.apply_changes(self.rig, self.p, new)
        except ParameterError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        if new["top_drive_mode"] != self.p["top_drive_mode"]:
            self._mode_left = (self.p["top_drive_mode"], time.monotonic())
        self.p = new
        if changed & set(session.RIG_FIELDS):
            self.get_logger().info(f"rig figures now: {session.figures_line(self.rig.params)}")
        if changed and self.recorder is not None:
            self.recorder.record_event("parameters", self.sim_time_s,
                                       {k: str(new[k]) for k in sorted(changed)})
        self.pacer.configure(new["rate_hz"], new["real_time_factor"], self._back_to_back(new))
        self._on_sample = new["measured_publish"] == "on_sample"
        self._steps_per_tick = self._tick_steps(new["rate_hz"])
        if self.lockstep is not None:
            self.lockstep.timeout_s = new["lockstep_timeout_s"]
        if changed & set(parameters.SPLITS) and self.recorder is not None:
            self.recorder.set_split(new["record_split_duration_s"],
                                    new["record_split_size_bytes"])
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

    def publish_diagnostics(self) -> None:
        """The status of ``core.diagnostics.rig_status`` as a DiagnosticArray."""
        now = time.monotonic()
        ticks = self.pacer.window(self.rig.time_s)
        metrics = self.rig.metrics()
        self.rig.reset_metrics_window()
        expected_hz = self.p["rate_hz"] * (1.0 if self.pacer.max_speed
                                           else min(1.0, self.p["real_time_factor"]))
        status = rig_status(
            self.rig.sample(), metrics, ticks, paused=self.paused,
            record_error=self.recorder.error if self.recorder is not None else None,
            command_age_s=now - self._cmd_wall, command_timeout_s=self.p["command_timeout_s"],
            rate_hz=expected_hz, max_speed=self.pacer.max_speed,
            lockstep=None if self.lockstep is None else self.lockstep.status(now),
            sim_time_s=self.sim_time_s, real_time_factor=self.p["real_time_factor"],
            other_publishers=self.other_publishers(),
            commands=CommandCounts(
                self.commands.received, self.superseded, self.commands.lost,
                self.commands.lost - self._lost_before))
        self._lost_before = self.commands.lost
        array = DiagnosticArray(status=[DiagnosticStatus(
            level=bytes([status.level]), name=f"{self.get_name()}: rig", message=status.message,
            hardware_id=self.preset.name,
            values=[KeyValue(key=k, value=v) for k, v in status.values.items()])])
        array.header.stamp = self.get_clock().now().to_msg()
        if self.recorder is None:
            self._diagnostics.publish(array)
        else:                                    # serialized once: published and recorded
            data = serialize_message(array)
            self._diagnostics.publish(data)
            self.recorder.record_diagnostics(data)


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
        node.rig.warm_up()   # load the compiled kernel before the first tick is due
        node.take_thread_priority()
        latency = node.request_cpu_latency()
        # The loops serve the executor (EventsExecutor: a fifth of the CPU of the
        # SingleThreadedExecutor) with spin_once between their ticks.
        if node.lockstep is not None:
            node.run_lockstep(executor, stop)
        elif node.pacer.max_speed:
            # ticks back to back, each taking the commands that came; services, parameters
            # and diagnostics once per wall millisecond; paused, a tick per wall millisecond
            next_spin = 0.0
            while not stop:
                node.tick()
                now = time.monotonic()
                if node.paused:
                    executor.spin_once(timeout_sec=1e-3)
                elif now >= next_spin:
                    node.serve(executor)
                    next_spin = now + SERVE_PERIOD_S
        else:
            node.run_real_time(executor, stop)
    except SystemExit as exc:     # a bad parameter at start-up: one clear line
        print(exc, file=sys.stderr)
        return 2
    finally:
        if node is not None:
            print(f"drill_sim_node: shut down at t = {node.sim_time_s:.3f} s", file=sys.stderr)
            if node.recorder is not None:
                node.recorder.close()
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
