"""``drill_sim_node``: the rig as a ROS 2 node. Surface commands in, bit and surface response out.

A thin adapter: each tick advances the core ``Rig`` to the current simulation time and
publishes its sample. Commands are validated in their callbacks and held (zero-order hold)
until the next tick; a refused command never reaches the model.
"""

from __future__ import annotations

import json
import math
import sys
import time
from functools import partial
from operator import attrgetter

import numpy as np
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from std_srvs.srv import SetBool, Trigger

from ..bag.writer import BagError
from ..core import NoSteadyDrilling, ParameterError, load_preset, session
from ..core.rig import RigSample
from ..wire import rig_topics
from ..wire.cdr import VECTOR_FIELDS
from ..wire.rig_messages import RigEncoders
from ..wire.rig_topics import RigTopic
from .parameters import specs
from .recorder import SessionRecorder
from .stopping import init_stoppable
from .topics import message_class, rclpy_qos, service_class

REGIME_NAMES = {True: "stick-slip", False: "drilling"}


class RigNode(Node):
    """The drilling rig node. Parameters, topics and services: msg_docs/node.md."""

    def __init__(self, **kwargs) -> None:
        super().__init__(rig_topics.NODE_NAME, **kwargs)
        self.declare_parameter("preset", "base", _read_only("preset name (base, shallow, deep) "
                                                            "or preset YAML file"))
        preset_name = self.get_parameter("preset").value
        try:
            self.preset = load_preset(preset_name)
        except ParameterError as exc:
            raise SystemExit(f"drill_sim_node: {exc}") from None
        self._specs = {s.name: s for s in specs(self.preset)}
        for spec in self._specs.values():
            self.declare_parameter(spec.name, spec.default, spec.descriptor())
        self.p = {name: self.get_parameter(name).value for name in self._specs}
        for name, spec in self._specs.items():
            if spec.choices and self.p[name] not in spec.choices:
                raise SystemExit(f"drill_sim_node: parameter {name} = {self.p[name]!r}: expected "
                                 f"one of {', '.join(spec.choices)}")
        try:
            self.rig = session.make_rig(self.p)
            session.start(self.rig, self.p)
        except (ParameterError, NoSteadyDrilling) as exc:
            raise SystemExit(f"drill_sim_node: {exc}") from None
        self.add_on_set_parameters_callback(self._on_set_parameters)

        # every topic and service from the table (wire.rig_topics)
        self.with_clock = bool(self.p["publish_clock"])
        self._enc = RigEncoders(self.with_clock)
        self._outputs = [self._publisher(t) for t in self._enc.topics]   # in publishing order
        self.pub_diag = self._publisher(rig_topics.of(rig_topics.DIAGNOSTICS)[0])
        self._commands = {t.name: self.create_subscription(
            message_class(t.type_name), t.name,
            partial(self._on_command, t, attrgetter(*VECTOR_FIELDS[t.type_name])),
            rclpy_qos(t.qos_for(self.p["qos_reliability"]))) for t in rig_topics.COMMANDS}
        handlers = {"~/reset": self._on_reset, "~/pause": self._on_pause, "~/step": self._on_step}
        for t in rig_topics.SERVICES:
            self.create_service(service_class(t.type_name), t.name, handlers[t.name])

        self._record_error: str | None = None
        self._output_names = [pub.topic_name for pub in self._outputs]
        self._events_topic = self.resolve_topic_name(rig_topics.EVENTS_TOPIC.name)
        self._offset_s = 0.0                     # simulated time before the last reset
        self.paused = False
        self._epoch_ns = time.time_ns()          # stamps = epoch + sim time without /clock
        self.recorder = self._start_recorder() if self.p["record"] else None
        self._anchor()
        self._tick_count = self._overruns = 0
        self._last_tick = None
        self._periods = np.zeros(int(4 * self.p["rate_hz"] * self.p["diagnostics_period_s"]) + 8)
        self._n_periods = 0
        self._diag_ticks = 0
        self._diag_wall = time.monotonic()
        self._diag_sim = self.rig.time_s
        self._cmd_wall = time.monotonic()
        self.timer = None
        if not self.max_speed:
            self.timer = self.create_timer(1.0 / self.p["rate_hz"], self.tick)
        self.create_timer(self.p["diagnostics_period_s"], self.publish_diagnostics)
        sc = self.rig.scales
        self.get_logger().info(
            f"rig '{self.preset.name}' ready: t* = {sc.time_s:.3f} s, dt = {self.rig.dt_s:.3g} s, "
            f"{self.p['rate_hz']:g} Hz, real-time factor "
            f"{'max' if self.max_speed else self.p['real_time_factor']}, "
            f"{'publishing /clock' if self.with_clock else 'wall-clock stamps'}")

    def _publisher(self, t: RigTopic):
        return self.create_publisher(message_class(t.type_name), t.name,
                                     rclpy_qos(t.qos_for(self.p["qos_reliability"])))

    # ---- time --------------------------------------------------------------------------
    @property
    def max_speed(self) -> bool:
        return bool(self.p["max_speed"] and self.p["publish_clock"])

    def _anchor(self) -> None:
        self._wall0 = time.monotonic()
        self._sim0 = self.rig.time_s

    def sim_target(self) -> float:
        if self.max_speed:
            return self.rig.time_s + 1.0 / self.p["rate_hz"]
        return self._sim0 + (time.monotonic() - self._wall0) * self.p["real_time_factor"]

    @property
    def sim_time_s(self) -> float:
        """Simulated time since the node started [s]; it keeps running across resets."""
        return self._offset_s + self.rig.time_s

    def stamp_ns(self) -> int:
        sim_ns = round(self.sim_time_s * 1e9)
        return sim_ns if self.with_clock else self._epoch_ns + sim_ns

    # ---- the tick ----------------------------------------------------------------------
    def tick(self) -> None:
        now = time.monotonic()
        if self._last_tick is not None:
            period = now - self._last_tick
            if self._n_periods < self._periods.size:
                self._periods[self._n_periods] = period
                self._n_periods += 1
            if period > 1.5 / self.p["rate_hz"] and not self.max_speed:
                self._overruns += 1
        self._last_tick = now
        if self.paused:
            return
        target = self.sim_target()
        # never try to catch up more than 0.1 s of simulated time in one tick
        self.rig.advance_to(min(target, self.rig.time_s + 0.1 * self.p["real_time_factor"]
                                + 1.0 / self.p["rate_hz"]))
        if target - self.rig.time_s > 0.1 * self.p["real_time_factor"]:
            self._anchor()                         # fell behind: drop the backlog
        self.publish_sample(self.rig.sample())
        self._tick_count += 1

    def publish_sample(self, s: RigSample) -> None:
        """Encode the sample once; publish those bytes and record the very same bytes."""
        data = self._enc.sample(self.stamp_ns(), s)
        for pub, raw in zip(self._outputs, data, strict=True):
            pub.publish(raw)
        if self.recorder is not None:
            self.recorder.record_many(self._output_names, data, time.time_ns())

    def _start_recorder(self) -> SessionRecorder | None:
        topics = {self.resolve_topic_name(t.name): (t.type_name, self.p["qos_reliability"])
                  for t in rig_topics.recorded(self.with_clock)}
        g, sc = self.rig.groups, self.rig.scales
        context = {
            "parameters": {k: str(v) for k, v in sorted(self.p.items())},
            "groups": {"n": str(g.n), "psi": repr(g.psi), "lambda": repr(g.lam),
                       "beta": repr(g.beta)},
            "scales": {"time_s": repr(sc.time_s), "length_m": repr(sc.length_m),
                       "force_n": repr(sc.force_n),
                       "stiffness_nm_per_rad": repr(sc.stiffness_nm_per_rad)},
        }
        context["session"] = {
            "preset": self.preset.name, "node": self.get_fully_qualified_name(),
            "stamp_epoch_ns": str(0 if self.with_clock else self._epoch_ns),
            "events_topic": self._events_topic}
        try:
            rec = SessionRecorder(self.p["record"], topics,
                                  reliability=self.p["qos_reliability"], context=context,
                                  logger=self.get_logger(),
                                  split_duration_s=self.p["record_split_duration_s"],
                                  split_size_bytes=self.p["record_split_size_bytes"])
        except (OSError, BagError) as exc:
            self.get_logger().error(f"not recording: {exc}; the simulation runs on")
            self._record_error = f"not recording: {exc}"
            return None
        self.get_logger().info(f"recording to {self.p['record']}")
        return rec

    def _record_event(self, kind: str, values: dict[str, str] | None = None) -> None:
        """Resets and parameter changes, so a re-simulation can do them at the same point."""
        if self.recorder is not None:
            self.recorder.record_event(self._events_topic, json.dumps(
                {"event": kind, "sim_time_s": self.sim_time_s, "values": values or {}}))

    # ---- commands ----------------------------------------------------------------------
    def _refuse(self, what: str, value: object, expected: str) -> None:
        self.get_logger().warning(f"refused {what} = {value!r}: expected {expected}; holding "
                                  "the last valid command", throttle_duration_sec=1.0)

    def _on_command(self, t: RigTopic, six_of: attrgetter, msg) -> None:
        """Recorded as received; used only if the session's rule accepts it (frame expected,
        value finite and in range), else the last valid command is held."""
        six = six_of(msg)
        header = msg.header
        if self.recorder is not None:
            self.recorder.record_command(self._commands[t.name].topic_name, header.frame_id,
                                         header.stamp.sec, header.stamp.nanosec, six)
        refusal = session.apply_command(self.rig, self.p, t.command, header.frame_id, six)
        if refusal is not None:
            self._refuse(*refusal)
        else:
            self._cmd_wall = time.monotonic()

    # ---- services ----------------------------------------------------------------------
    def _on_reset(self, request: Trigger.Request, response: Trigger.Response):
        offset = self._offset_s + self.rig.time_s
        try:
            session.start(self.rig, self.p)
        except (ParameterError, NoSteadyDrilling) as exc:
            response.success, response.message = False, str(exc)
            return response
        self._record_event("reset")
        self._offset_s = offset
        self._anchor()
        self._diag_sim = self.rig.time_s
        self.publish_sample(self.rig.sample())
        response.success = True
        response.message = f"reset to the initial state ({self.p['initial_state']})"
        return response

    def _on_pause(self, request: SetBool.Request, response: SetBool.Response):
        if self.paused and not request.data:
            self._anchor()
        self.paused = bool(request.data)
        response.success = True
        response.message = "paused" if self.paused else "running"
        return response

    def _on_step(self, request: Trigger.Request, response: Trigger.Response):
        if not self.paused:
            response.success, response.message = False, "step works only while paused"
            return response
        self.rig.advance_to(self.rig.time_s + 1.0 / self.p["rate_hz"] * self.p["real_time_factor"])
        self.publish_sample(self.rig.sample())
        response.success = True
        response.message = f"stepped to t = {self.sim_time_s:.6f} s"
        return response

    # ---- parameters at run time --------------------------------------------------------
    def _on_set_parameters(self, params) -> SetParametersResult:
        new = dict(self.p)
        for param in params:
            if param.name not in new:
                continue
            spec = self._specs[param.name]
            value = param.value
            if spec.choices and value not in spec.choices:
                return SetParametersResult(successful=False, reason=f"{param.name} = {value!r}: "
                                           f"expected one of {', '.join(spec.choices)}")
            if isinstance(value, float) and not math.isfinite(value):
                return SetParametersResult(successful=False,
                                           reason=f"{param.name} = {value!r} is not finite")
            new[param.name] = value
        try:
            changed = session.apply_changes(self.rig, self.p, new)
        except ParameterError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        self.p = new
        if changed:
            self._record_event("parameters", {k: str(new[k]) for k in sorted(changed)})
        if "real_time_factor" in changed:
            self._anchor()
        if "rate_hz" in changed and self.timer is not None:
            self.timer.cancel()
            self.destroy_timer(self.timer)
            self.timer = self.create_timer(1.0 / new["rate_hz"], self.tick)
        return SetParametersResult(successful=True)

    # ---- diagnostics -------------------------------------------------------------------
    def publish_diagnostics(self) -> None:
        now = time.monotonic()
        wall = max(now - self._diag_wall, 1e-9)
        rate = self._tick_count - self._diag_ticks
        rtf = (self.rig.time_s - self._diag_sim) / wall
        metrics = self.rig.metrics()
        self.rig.reset_metrics_window()
        self._diag_ticks, self._diag_wall, self._diag_sim = self._tick_count, now, self.rig.time_s
        s = self.rig.sample()
        age = now - self._cmd_wall
        if s.off_bottom:
            regime = "off bottom"
        elif metrics["bounce_fraction"] > 0:
            regime = "bouncing"
        else:
            regime = REGIME_NAMES[s.stick_slip]
        status = DiagnosticStatus(name=f"{self.get_name()}: rig", hardware_id=self.preset.name)
        status.level, status.message = DiagnosticStatus.OK, regime
        record_error = self._record_error or (self.recorder.error if self.recorder else None)
        if record_error:
            status.level = DiagnosticStatus.ERROR
            status.message = record_error
        elif self.paused:
            status.message = "paused"
        elif age > self.p["command_timeout_s"]:
            status.level = DiagnosticStatus.WARN
            status.message = f"no command for {age:.1f} s (timeout {self.p['command_timeout_s']:g}"
            status.message += " s); holding the last valid command"
        elif self._overruns and not self.max_speed and rate < 0.9 * self.p["rate_hz"] * wall:
            status.level = DiagnosticStatus.WARN
            status.message = f"tick rate {rate / wall:.0f} Hz below {self.p['rate_hz']:g} Hz"
        periods = self._periods[:self._n_periods]
        p99 = float(np.percentile(periods, 99)) * 1e3 if periods.size else math.nan
        self._n_periods = 0
        values = {
            "tick_rate_hz": f"{rate / wall:.1f}", "tick_period_p99_ms": f"{p99:.3f}",
            "overruns": str(self._overruns),
            "real_time_factor": f"{rtf:.3f}", "regime": regime, "ssi": f"{metrics['ssi']:.3f}",
            "stick_fraction": f"{metrics['stick_fraction']:.3f}",
            "command_age_s": f"{age:.3f}", "sim_time_s": f"{self.sim_time_s:.3f}",
            "paused": str(self.paused).lower(),
        }
        status.values = [KeyValue(key=k, value=v) for k, v in values.items()]
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.get_clock().now().to_msg()
        self.pub_diag.publish(array)


def _read_only(description: str) -> ParameterDescriptor:
    return ParameterDescriptor(description=description, read_only=True)


def main(args: list[str] | None = None) -> int:
    # SIGINT/SIGTERM only raise a flag, so the node always stops between two ticks: no tick
    # is cut in half (published but not recorded, or recorded in part).
    stop = init_stoppable(args)
    node = executor = None
    try:
        node = RigNode()
        executor = EventsExecutor()
        executor.add_node(node)
        node.rig.warm_up()   # load the compiled kernel before the first tick is due
        # EventsExecutor.spin() does not dispatch timers in this rclpy; spin_once() does, at
        # 1 kHz with p99 period ~1.08 ms and a fifth of the CPU of SingleThreadedExecutor.
        if node.max_speed:
            # ticks back to back; commands, services and diagnostics once per wall millisecond
            next_spin = 0.0
            while not stop:
                node.tick()
                now = time.monotonic()
                if now >= next_spin:
                    executor.spin_once(timeout_sec=0.0)
                    next_spin = now + 1e-3
        else:
            while not stop:
                executor.spin_once(timeout_sec=0.1)
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
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
