"""In-node recording: every topic the node publishes and every command it receives, into a
rosbag2 MCAP bag (``drill_sim.bag.writer``), with the session's context (parameters,
dimensionless groups, scales, the rig's key figures, preset, node) as MCAP metadata, which
``drill_sim bag resim`` needs to re-run the session. Which topics, of which types, come from
the topics table.
Outputs are recorded as the very bytes the node published, commands as the very bytes it
received; events are encoded here (``drill_sim.wire.cdr``).

A bag that cannot be opened refuses the start (``RecordRefused``); a recording problem later
(full disk, a split file that cannot be created) stops the recording with a clear error and
leaves the simulation running; the bag written so far stays readable.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from .. import __version__
from ..bag.writer import BagError, BagWriter
from ..core.figures import key_figures
from ..core.rig import Rig
from ..core.sensor_profile import SensorProfile
from ..wire import WireError, cdr, rig_topics
from ..wire.rig_topics import RigTopic
from .rules import geometry_record


class RecordRefused(Exception):
    """The bag of ``record`` cannot be opened (it exists, its folder does not, no room...)."""


class SessionRecorder:
    """Records one rig session into the new bag directory named by the ``record`` parameter.
    Raises RecordRefused only at start, when the bag cannot be opened; after that never:
    ``error`` says why it does not record any more, for the node's diagnostics."""

    def __init__(self, *, p: dict[str, object], rig: Rig, preset: str, node: str,
                 resolve: Callable[[str], str], stamp_epoch_ns: int, logger,
                 sensors: SensorProfile | None = None) -> None:
        """p: the node's parameters at start; node: its fully qualified name; resolve: a
        table name to the full topic name (the node's remappings applied); stamp_epoch_ns:
        what output stamps count from [ns] (0 with /clock); sensors: the sensor profile in
        use, recorded whole (a profile file may change or vanish after the session)."""
        self.logger = logger
        self.error: str | None = None
        with_clock = bool(p["publish_clock"])
        self.names = {t.name: resolve(t.name) for t in rig_topics.recorded(with_clock)}
        self.outputs = [self.names[t.name] for t in rig_topics.published(with_clock)]
        self.events_topic = self.names[rig_topics.EVENTS_TOPIC.name]
        self.diagnostics_topic = self.names[rig_topics.DIAGNOSTICS_TOPIC.name]
        meta = {"session": {"package": "drill_sim", "version": __version__,
                            "start_time_ns": str(time.time_ns()),
                            "command_line": json.dumps(sys.argv)}}
        for name, values in _context(p, rig, preset, node, stamp_epoch_ns,
                                     self.events_topic).items():
            meta.setdefault(name, {}).update(values)
        if sensors is not None:
            meta["sensors"] = {"name": sensors.name, "profile": json.dumps(sensors.as_dict())}
        # Every topic is recorded as offered with the session's qos_reliability (so /clock
        # too, though its publisher is always reliable): bags keep the form they always had;
        # /diagnostics, recorded since, with the QoS it is offered with.
        offered = rig_topics.RIG_QOS.with_reliability(str(p["qos_reliability"]))
        try:
            self.writer = BagWriter(Path(str(p["record"])), metadata=meta,
                                    split_duration_s=p["record_split_duration_s"],
                                    split_size_bytes=p["record_split_size_bytes"])
            for t in rig_topics.recorded(with_clock):
                qos = t.qos if t is rig_topics.DIAGNOSTICS_TOPIC else offered
                self.writer.add_topic(self.names[t.name], t.type_name, [qos.as_dict()])
        except BagError as exc:
            # at start nothing has run yet: the node refuses to start (a session asked to
            # be recorded and not recorded would be lost); a failure later leaves it running
            raise RecordRefused(str(exc)) from None
        except OSError as exc:
            raise RecordRefused(f"bag {p['record']}: cannot write it: {exc.strerror}; expected "
                                "a new bag directory in an existing folder") from None
        logger.info(f"recording to {p['record']}")

    def set_split(self, duration_s: float, size_bytes: int) -> None:
        """New split limits (0: never), from the next message on."""
        if self.error is None:
            self.writer.split_duration_ns = int(duration_s * 1e9)
            self.writer.split_size_bytes = int(size_bytes)

    def record_outputs(self, data: list[bytes], held: Sequence[int] = ()) -> None:
        """One tick's outputs as published, in the table's publishing order, received and
        published now; those at ``held`` (indices) were not published and are left out."""
        if self.error is None:
            write, now = self.writer.write, time.time_ns()
            try:
                for k, (topic, raw) in enumerate(zip(self.outputs, data, strict=True)):
                    if k not in held:
                        write(topic, raw, now, now)
            except (OSError, BagError) as exc:
                self._stop(exc)

    def record_command(self, t: RigTopic, data: bytes, sec: int, nanosec: int) -> None:
        """A command's bytes as received, logged now and published at its stamp ``sec``,
        ``nanosec`` (now if stamped before 1970: that cannot be a time)."""
        if self.error is None:
            now, sent = time.time_ns(), sec * 1_000_000_000 + nanosec
            try:
                self.writer.write(self.names[t.name], data, now, sent if sent >= 0 else now)
            except (OSError, BagError) as exc:
                self._stop(exc)

    def record_diagnostics(self, data: bytes) -> None:
        """A /diagnostics message as published (CDR bytes), received and published now."""
        if self.error is None:
            now = time.time_ns()
            try:
                self.writer.write(self.diagnostics_topic, data, now, now)
            except (OSError, BagError) as exc:
                self._stop(exc)

    def record_event(self, kind: str, sim_time_s: float,
                     values: dict[str, str] | None = None) -> None:
        """A reset or parameter change at session time ``sim_time_s`` [s], so a re-simulation
        can do it at the same point."""
        if self.error is None:
            now = time.time_ns()
            text = json.dumps({"event": kind, "sim_time_s": sim_time_s, "values": values or {}})
            try:
                self.writer.write(self.events_topic, cdr.string(text), now, now)
            except (OSError, BagError, WireError) as exc:
                self._stop(exc)

    def _stop(self, exc: Exception) -> None:
        self.error = f"recording stopped: {exc}"
        self.logger.error(self.error + "; the simulation keeps running")
        try:
            self.writer.close()
        except (OSError, BagError):
            pass

    def close(self) -> None:
        if self.error is None:
            try:
                self.writer.close()
            except (OSError, BagError) as exc:
                self.logger.error(f"closing the bag failed: {exc}")


def _context(p: dict[str, object], rig: Rig, preset: str, node: str, stamp_epoch_ns: int,
             events_topic: str) -> dict[str, dict[str, str]]:
    """The session's MCAP metadata records (name -> {key: text}); msg_docs/bag.md."""
    g, sc = rig.groups, rig.scales
    return {
        "parameters": {k: str(v) for k, v in sorted(p.items())},
        "groups": {"n": str(g.n), "psi": repr(g.psi), "lambda": repr(g.lam),
                   "beta": repr(g.beta)},
        "scales": {"time_s": repr(sc.time_s), "length_m": repr(sc.length_m),
                   "force_n": repr(sc.force_n),
                   "stiffness_nm_per_rad": repr(sc.stiffness_nm_per_rad)},
        "figures": {k: repr(v) for k, v in key_figures(rig.params).items()},
        "session": {"preset": preset, "node": node, "stamp_epoch_ns": str(stamp_epoch_ns),
                    "events_topic": events_topic, "step_s": repr(rig.dt_s)},
    } | ({"string": geometry_record(rig.geometry)}          # the pipe, or the formations
         if rig.geometry is not None and (rig.string_model == "distributed" or rig.formations)
         else {})
