"""What a session's bag says about its drive and its events, for the figures ``core.effort``
gives: the drive's motor-torque limits (the recorded start parameters) and the stamps of the
controller switches the rig recorded on its ``~/events``. A bag the rig node did not write has
neither (the figures that need them are then None)."""

from __future__ import annotations

import json
import math
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.effort import EffortStats, Figures
from ..wire import WireError, rig_topics
from ..wire.cdr_decode import decode_command
from .bag import Bag, opened
from .series import RigSeries, columns, joint_chunks, joint_topic
from .stamped_series import MOTOR, matched


@dataclass(frozen=True)
class SessionEvents:
    """``torque_limits_nm``: (min, max) of the drive's motor torque [N·m], None for a kinematic
    drive or a bag without the rig's parameters; ``switches_ns``: header-stamp times [ns] of the
    controller switches; ``events``: every recorded event as (stamp [ns], kind, values)."""

    torque_limits_nm: tuple[float, float] | None = None
    switches_ns: tuple[int, ...] = ()
    events: list[tuple[int, str, dict]] = field(default_factory=list)


def session_events(bag: Bag) -> SessionEvents:
    """The drive's limits and the recorded events of a session bag (empty when it has none)."""
    meta = bag.metadata
    params = meta.get("parameters", {})
    session = meta.get("session", {})
    limits = None
    try:
        low = float(params["motor_torque_min_nm"])
        high = float(params["motor_torque_max_nm"])
        if params.get("top_drive_mode", "kinematic") != "kinematic" and math.isfinite(low) \
                and math.isfinite(high) and low < high:
            limits = (low, high)
    except (KeyError, ValueError):
        pass
    if "node" not in session:
        return SessionEvents(limits)
    epoch_ns = int(session.get("stamp_epoch_ns", "0") or 0)
    topic = session.get("events_topic", rig_topics.EVENTS_TOPIC.under(session["node"]))
    events: list[tuple[int, str, dict]] = []
    if topic in bag.topic_types():
        for m in bag.messages({topic}, []):
            event = _decoded(m.data)
            if event is not None:
                at = event.get("sim_time_s")
                if isinstance(at, (int, float)) and math.isfinite(at):
                    events.append((epoch_ns + round(at * 1e9), str(event.get("event")),
                                   event.get("values") or {}))
    return SessionEvents(limits, tuple(ns for ns, kind, _ in events if kind == "controller"),
                         events)


def _decoded(data: bytes) -> dict | None:
    """A std_msgs/String event of the rig (JSON), None if it is not one."""
    try:
        (n,) = struct.unpack_from("<I", data, 4)
        event = json.loads(data[8:8 + n - 1].decode("utf-8"))
    except (struct.error, UnicodeDecodeError, ValueError):
        return None
    return event if isinstance(event, dict) else None


@dataclass(frozen=True)
class BagSession:
    """A session's bag read in one pass over its samples: the rig series, the motor torque
    [N·m] its ``~/top_drive/motor_wrench`` recorded at those samples (None: it has none;
    NaN where a sample has none), the ``core.effort`` figures and its events."""

    series: RigSeries
    motor_torque_nm: np.ndarray | None
    effort: Figures
    events: SessionEvents


def read_session(bag: str | Path | Bag, events_s: list[float] | None = None,
                 window_start_s: float = -math.inf,
                 problems: list[str] | None = None) -> BagSession:
    """The session in ``bag`` (its one joint_states topic), in memory. The effort's settling
    counts from ``events_s`` [s after the first sample] when given, else from the controller
    switches the rig recorded; its figures from ``window_start_s`` [s after the first sample]
    on. Damage goes into ``problems``; BagError when there are no samples."""
    with opened(bag) as b:
        name = joint_topic(b, None)
        facts = session_events(b)
        motor = next((m for spec, m in matched(b, name, (MOTOR,)) if spec is MOTOR), None)
        chunks = list(joint_chunks(b, name, [] if problems is None else problems))
        series = RigSeries.from_chunks(name, chunks)
        first = chunks[0][0]
        origin = int(first[0]) if first.size else 0
        stats = EffortStats(facts.torque_limits_nm, events_s if events_s is not None
                            else [(at - origin) / 1e9 for at in facts.switches_ns],
                            window_start_s)
        torques = []
        for ns, values in chunks:
            named = columns(values)
            torque = None if motor is None else motor.at(ns)[:, 0]
            stats.add((ns - origin) / 1e9, named["bit_speed_rad_s"], torque,
                      named["top_drive_speed_rad_s"])
            if torque is not None:
                torques.append(torque)
        return BagSession(series, None if motor is None else np.concatenate(torques),
                          stats.result(), facts)


def speed_setpoints(bag: Bag, joint_topic: str) -> tuple[np.ndarray, np.ndarray]:
    """The top-drive speed commands the rig took, as recorded on its ``~/cmd/top_drive``
    (header stamps [ns], angular z [rad/s]); empty when the bag has none."""
    suffix = rig_topics.JOINT_STATES.name[1:]
    topic = rig_topics.topic("~/cmd/top_drive")
    name = joint_topic[:-len(suffix)] + topic.name[1:] if joint_topic.endswith(suffix) else ""
    stamps, speeds = [], []
    if bag.topic_types().get(name) == topic.type_name:
        for m in bag.messages({name}, []):
            try:
                _, sec, nanosec, six = decode_command(topic.type_name, m.data)
            except WireError:
                continue
            stamps.append(sec * 1_000_000_000 + nanosec)
            speeds.append(six[5])
    order = np.argsort(np.asarray(stamps, np.int64), kind="stable")
    return np.asarray(stamps, np.int64)[order], np.asarray(speeds, float)[order]
