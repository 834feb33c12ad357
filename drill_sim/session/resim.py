"""Re-running a recorded rig session from its bag, and how far the re-run is from the recording.

The node records its parameters (MCAP metadata), every command it received, its resets and
run-time parameter changes (``<node>/events``) and every sample it published, in the order they
happened. The re-run runs the same ``RigSession`` the node ran, then walks the bag in that order:
each command is accepted or refused by the node's rules, each event is redone, and before each
recorded joint_states sample the model is advanced to that sample's step and compared with it.
The sensors (``core.sensors``, the recorded profile and seed) measure each re-run sample as the
node did, and the ``~/measured/`` messages that follow are compared with their reading.
The model is deterministic and the node only advances it between samples, so the re-run is
exact in both modes: in sim-time mode the ticks are fixed steps of simulated time; in
real-time mode they came from the wall clock, and the re-run takes them from the stamps.
"""

from __future__ import annotations

import json
import math
import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

from ..bag.bag import Bag, opened
from ..bag.errors import BagError
from ..bag.series import JOINT_ARRAY_START, JOINT_FIELDS, JOINT_VALUES_F64, joint_state_layout
from ..core import NoSteadyDrilling, ParameterError
from ..core.sensor_profile import profile_from_dict
from ..core.sensors import Measured
from ..wire import cdr, cdr_decode, rig_topics
from . import rules
from .rig_session import RigSession

_STAMP = struct.Struct("<iI")
MOTOR_TORQUE = "motor_torque_nm"            # compared from ~/top_drive/motor_wrench when recorded
_JOINT_VALUES = struct.Struct(f"<{JOINT_VALUES_F64}d")


@dataclass
class ResimResult:
    """What the re-run found. ``max_difference``: largest |re-run - recorded| per quantity
    (SI units as named); ``worst``: (quantity, difference, simulated time [s])."""

    bag: Path
    mode: str                                    # "sim-time" or "real-time"
    preset: str
    samples: int = 0
    commands: int = 0
    refused: int = 0
    events: list[str] = field(default_factory=list)
    max_difference: dict[str, float] = field(
        default_factory=lambda: dict.fromkeys((*JOINT_FIELDS, MOTOR_TORQUE), 0.0))
    worst: tuple[str, float, float] = ("", 0.0, 0.0)
    problems: list[str] = field(default_factory=list)

    @property
    def matched(self) -> bool:
        """Every sample read equals the re-run bit for bit."""
        return self.samples > 0 and all(v == 0.0 for v in self.max_difference.values())

    @property
    def exact(self) -> bool:
        """The whole session reproduced: every sample matched and none is missing."""
        return self.matched and not self.problems

    def explanation(self) -> str:
        """Why the re-run matches or not, in words."""
        if self.matched and self.problems:
            return ("every sample read equals the re-run bit for bit, but the bag is "
                    "incomplete, so only part of the session was compared and this is no "
                    "reproduction of the whole session: " + "; ".join(self.problems))
        if self.exact:
            return ("reproduced exactly: every recorded sample equals the re-run bit for bit"
                    + (" (real-time mode: the ticks' simulated times come from the recorded "
                       "stamps, so wall-clock jitter does not enter)"
                       if self.mode == "real-time" else ""))
        why = []
        if self.problems:
            why.append("the bag is damaged or was cut short (" + "; ".join(self.problems) + ")")
        why.append("messages missing from the recording (a crash, a full disk, or a recording "
                   "that was not the node's own) leave commands, resets or parameter changes "
                   "out of the re-run")
        if self.mode == "real-time":
            why.append("in real-time mode a command lands on the tick that follows its arrival "
                       "on the wall clock; the re-run can only follow the order the bag kept")
        return "differs from the recording; likely causes: " + "; ".join(why)


def resimulate(bag: str | Path | Bag, progress: Callable[[float], None] | None = None
               ) -> ResimResult:
    """Re-run the session recorded in ``bag`` and compare it sample by sample."""
    with opened(bag) as b:
        return _resimulate(b, progress)


def _resimulate(bag: Bag, progress: Callable[[float], None] | None) -> ResimResult:
    found = bag.info(verify=False)              # the walk below checks every chunk
    meta = found.metadata
    if "parameters" not in meta or "node" not in meta.get("session", {}):
        raise BagError(f"bag {bag.path}: no drill_sim session metadata (parameters, session); "
                       "resim re-runs sessions the rig node recorded itself")
    p = {k: rules.parse_value(v) for k, v in meta["parameters"].items()}
    node = meta["session"]["node"]
    epoch_ns = int(meta["session"].get("stamp_epoch_ns", "0"))
    topics = {"joints": rig_topics.JOINT_STATES.under(node),
              "events": meta["session"].get("events_topic", rig_topics.EVENTS_TOPIC.under(node))}
    if topics["joints"] not in found.topics:
        raise BagError(f"bag {bag.path}: no {topics['joints']} to compare with")
    result = ResimResult(bag.path, "sim-time" if p.get("publish_clock") else "real-time",
                         meta["session"].get("preset", "?"))
    try:
        # the step the node used; bags from before it was recorded ran at dt_s itself
        geometry = rules.geometry_from_record(meta["string"]) if "string" in meta else None
        recorded = meta.get("sensors", {})
        profile = profile_from_dict(recorded.get("name", "recorded"),
                                    json.loads(recorded["profile"])) \
            if "profile" in recorded else None
        session = RigSession(p, geometry=geometry, sensor_profile=profile, record=False,
                             step_s=float(meta["session"].get("step_s", p["dt_s"])))
    except (ParameterError, NoSteadyDrilling, KeyError, ValueError) as exc:
        raise BagError(f"bag {bag.path}: the recorded parameters do not make a rig: {exc}") \
            from None
    run = _Rerun(session, epoch_ns, result)
    total = max(found.topics[topics["joints"]].count, 1)
    handlers = {topics["joints"]: run.sample, topics["events"]: run.event,
                rig_topics.topic("~/top_drive/motor_wrench").under(node): run.motor}
    handlers.update({t.under(node): partial(run.command, t) for t in rig_topics.COMMANDS})
    handlers.update({t.under(node): partial(run.measured, t)
                     for t in rig_topics.MEASURED_OUTPUTS if t.under(node) in found.topics})
    walked: list[str] = []
    for m in bag.messages(set(handlers), walked):
        handlers[m.topic](m.data)
        if progress is not None and m.topic == topics["joints"]:
            progress(result.samples / total)
    # a repair's lost end (a crash) is only a note of the bag, but the session went on past
    # it: the part kept is all that was compared
    gaps, lost_ends = bag.repaired()
    result.problems = list(dict.fromkeys(found.problems + walked + gaps + lost_ends))
    return result


class _Rerun:
    """The recorded session walked through a ``RigSession``: the object the node ran."""

    def __init__(self, session: RigSession, epoch_ns: int, result: ResimResult) -> None:
        self.session, self.rig, self.epoch_ns, self.result = session, session.rig, epoch_ns, result
        self.reading: Measured | None = None     # the sensors' reading of the last sample
        self.values_at: int | None = None        # byte offset of the joint arrays
        self.types = {t.command: t.type_name for t in rig_topics.COMMANDS}

    def _advance(self, data: bytes) -> float:
        """To the step of a recorded output's stamp; its simulated time [s]."""
        sec, nsec = _STAMP.unpack_from(data, 4)
        sim_time_s = (sec * 1_000_000_000 + nsec - self.epoch_ns) * 1e-9
        step = round((sim_time_s - self.session.offset_s) / self.rig.dt_s)
        ahead = step - self.rig.steps
        if ahead > 0:
            self.rig.advance_steps(ahead)
        return sim_time_s

    def sample(self, data: bytes) -> None:
        if self.values_at is None:
            self.values_at = joint_state_layout(data)[1]
        sim_time_s = self._advance(data)
        recorded = _JOINT_VALUES.unpack_from(data, self.values_at)
        s = self.rig.sample()
        for name, (kind, j) in JOINT_FIELDS.items():
            self._compare(name, getattr(s, name), recorded[JOINT_ARRAY_START[kind] + j],
                          sim_time_s)
        self.reading = self.session.sensors.measure(self.rig.time_s, s)
        self.result.samples += 1

    def motor(self, data: bytes) -> None:
        """A recorded motor torque (published after the tick's joint_states, at its step)."""
        sim_time_s = self._advance(data)
        torque_nm = cdr_decode.decode_stamped_vectors(data)[3][5]
        self._compare(MOTOR_TORQUE, self.rig.motor_torque_nm, torque_nm, sim_time_s)

    def measured(self, t: rig_topics.RigTopic, data: bytes) -> None:
        """A recorded ~/measured/ message against the sensors' reading of the re-run sample
        it followed (a message before any sample, or one that cannot be decoded, counts as
        different)."""
        values = _measured_values(t, data)
        for f in t.fields:
            rerun = getattr(self.reading, f.sample) if self.reading is not None else math.nan
            self._compare(f"measured {f.sample}", rerun, values.get(f.message, math.nan),
                          self.session.sim_time_s)

    def _compare(self, name: str, rerun: float, recorded: float, t: float) -> None:
        r = self.result
        diff = abs(rerun - recorded)
        if not diff <= r.max_difference.setdefault(name, 0.0):      # also catches NaN
            r.max_difference[name] = diff if not math.isnan(diff) else math.inf
            if r.max_difference[name] > r.worst[1]:
                r.worst = (name, r.max_difference[name], t)

    def command(self, topic: rig_topics.RigTopic, data: bytes) -> None:
        """A recorded command, accepted or refused by the session's own rule."""
        frame, _, _, six = cdr_decode.decode_command(topic.type_name, data)
        if self.session.commands.command(topic, frame, six) is None:
            self.result.commands += 1
        else:
            self.result.refused += 1

    def event(self, data: bytes) -> None:
        (n,) = struct.unpack_from("<I", data, 4)
        event = json.loads(data[8:8 + n - 1].decode("utf-8"))
        kind = event.get("event")
        if kind == "reset":
            self.session.reset(None)
        elif kind == "parameters":
            new = dict(self.session.p)
            new.update({k: rules.parse_value(v) for k, v in event["values"].items()})
            self.session.change(new)
        self.result.events.append(kind)


def _measured_values(t: rig_topics.RigTopic, data: bytes) -> dict[str, float]:
    """The float64 fields of a recorded ~/measured/ message by path ({} if undecodable)."""
    try:
        if t.type_name in cdr.VECTOR_FIELDS:
            six = cdr_decode.decode_stamped_vectors(data)[3]
            return dict(zip(cdr.VECTOR_FIELDS[t.type_name], six, strict=True))
        return {"data": struct.unpack_from("<d", data, 4)[0]}
    except (cdr.WireError, struct.error):
        return {}
