"""The rig's time series from a bag, decoded without ROS, a chunk at a time.

The node's ``~/joint_states`` messages have one fixed layout within a session (same four joint
names, so the same byte length), so a chunk's CDR bytes stack into one array and the float
fields are read with a single numpy view: an hour at 1 kHz decodes in a fraction of a second.
The chunks stream (``joint_chunks``), so tools that sum over them keep memory bounded.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core.stick_slip import stuck
from ..wire.rig_topics import JOINT_NAMES, JOINT_PLACES, JOINT_STATES
from .bag import Bag, opened
from .errors import BagError
from .mcap_index import channel_chunks
from .rig_stats import QUANTITIES, RigStats

JOINT_STATE = JOINT_STATES.type_name
# the quantities of a rig series (the joint_states' angles are not among them), and where each
# sits in the node's joint_states: (array, joint index), from the topics table
JOINT_FIELDS = {name: JOINT_PLACES[name] for name in (
    "top_drive_speed_rad_s", "surface_torque_nm", "hook_load_n", "bit_depth_m", "bit_speed_rad_s",
    "tob_nm", "hole_depth_m", "rop_m_s", "wob_n")}
# From the position array on, the rig's joint_states is 14 float64 slots: position[4], then a
# uint32 count and 4 bytes of padding (one slot), velocity[4], another slot, effort[4].
JOINT_VALUES_F64 = 14
JOINT_ARRAY_START = {"position": 0, "velocity": 5, "effort": 10}
# the column of each quantity in the (N, 12) values ``joint_chunks`` yields
VALUE_COLUMN = {name: 4 * ("position", "velocity", "effort").index(kind) + j
                for name, (kind, j) in JOINT_FIELDS.items()}
JointChunk = tuple[np.ndarray, np.ndarray]       # header stamps [ns] int64, (N, 12) values


@dataclass(frozen=True)
class RigSeries:
    """SI time series of one rig, from its joint_states (see msg_docs/node.md)."""

    topic: str
    time_s: np.ndarray                 # header stamp
    top_drive_speed_rad_s: np.ndarray
    surface_torque_nm: np.ndarray
    hook_load_n: np.ndarray
    bit_depth_m: np.ndarray
    bit_speed_rad_s: np.ndarray
    tob_nm: np.ndarray
    hole_depth_m: np.ndarray
    rop_m_s: np.ndarray
    wob_n: np.ndarray

    @classmethod
    def from_joints(cls, topic: str, time_s: np.ndarray, position: np.ndarray,
                    velocity: np.ndarray, effort: np.ndarray) -> RigSeries:
        """From (N, 4) joint arrays in the order of JOINT_NAMES."""
        arrays = {"position": position, "velocity": velocity, "effort": effort}
        return cls(topic, np.asarray(time_s, float), **{
            name: np.ascontiguousarray(arrays[kind][:, j]) for name, (kind, j)
            in JOINT_FIELDS.items()})

    @classmethod
    def from_chunks(cls, topic: str, chunks: list[JointChunk]) -> RigSeries:
        """From ``joint_chunks`` (stamps [ns], (N, 12) values); BagError if they are empty."""
        if not any(ns.size for ns, _ in chunks):
            raise BagError(f"{topic}: no samples in the bag or the window")
        ns = np.concatenate([c[0] for c in chunks])
        v = np.concatenate([c[1] for c in chunks])
        return cls.from_joints(topic, ns * 1e-9, v[:, 0:4], v[:, 4:8], v[:, 8:12])

    @property
    def stuck(self) -> np.ndarray:
        """Samples with the bit stuck: not rotating while pressed on the rock."""
        return stuck(self.bit_speed_rad_s, self.wob_n)

    def window(self, start_s: float | None, end_s: float | None) -> RigSeries:
        t = self.time_s - self.time_s[0] if self.time_s.size else self.time_s
        keep = np.ones(t.size, bool)
        if start_s is not None:
            keep &= t >= start_s
        if end_s is not None:
            keep &= t <= end_s
        return RigSeries(self.topic, *(getattr(self, f)[keep] for f in _FIELDS))

    def metrics(self) -> dict[str, float]:
        """MODEL.md section 7 over the samples (``rig_stats.RigStats``)."""
        stats = RigStats(self.topic)
        t = self.time_s - self.time_s[0] if self.time_s.size else self.time_s
        stats.add(t, {q: getattr(self, q) for q in QUANTITIES})
        return stats.result()


_FIELDS = ("time_s", "top_drive_speed_rad_s", "surface_torque_nm", "hook_load_n", "bit_depth_m",
           "bit_speed_rad_s", "tob_nm", "hole_depth_m", "rop_m_s", "wob_n")


def joint_state_layout(data: bytes) -> tuple[list[str], int]:
    """Joint names and the byte offset of the position array in one JointState message."""
    def align(pos: int, n: int) -> int:
        body = pos - 4                          # alignment counts from after the 4-byte header
        return pos + (-body) % n

    pos = 4 + 8                                 # encapsulation header, stamp
    (length,) = struct.unpack_from("<I", data, pos)
    pos = align(pos + 4 + length, 4)            # frame_id
    (count,) = struct.unpack_from("<I", data, pos)
    pos += 4
    names = []
    for _ in range(count):
        pos = align(pos, 4)
        (length,) = struct.unpack_from("<I", data, pos)
        names.append(data[pos + 4:pos + 3 + length].decode())
        pos += 4 + length
    pos = align(pos, 4)
    (n_pos,) = struct.unpack_from("<I", data, pos)
    if n_pos != count:
        raise BagError(f"joint_states with {count} names but {n_pos} positions")
    return names, align(pos + 4, 8)


def columns(values: np.ndarray) -> dict[str, np.ndarray]:
    """The (N, 12) values of ``joint_chunks`` as one column per quantity."""
    return {name: values[:, k] for name, k in VALUE_COLUMN.items()}


def joint_topic(bag: Bag, topic: str | None = None) -> str:
    """The rig's joint_states topic: ``topic`` if the bag has it, else the one JointState
    topic, the rig's ``.../joint_states`` first (the node also records the JointState
    commands it receives); BagError if there is none or several."""
    joint_topics = sorted(t for t, kind in bag.topic_types().items()
                          if kind == JOINT_STATE and (topic is None or t == topic))
    outputs = [t for t in joint_topics if t.endswith(JOINT_STATES.name[1:])]
    if topic is None and len(outputs) == 1:
        joint_topics = outputs
    if not joint_topics:
        found = sorted(t for t, kind in bag.topic_types().items() if kind == JOINT_STATE)
        raise BagError(f"bag {bag.path}: no {JOINT_STATE} topic"
                       f"{'' if topic is None else ' ' + topic} to read the rig from"
                       + (f" (its {JOINT_STATE} topics: {', '.join(found)})"
                          if topic is not None and found else ""))
    if len(joint_topics) > 1:
        raise BagError(f"bag {bag.path}: several joint_states topics "
                       f"({', '.join(joint_topics)}); choose one with --topic")
    return joint_topics[0]


def joint_chunks(bag: Bag, name: str, problems: list[str]) -> Iterator[JointChunk]:
    """The samples of the joint_states topic ``name``, a chunk at a time in file order: header
    stamps [ns] and (N, 12) values (``VALUE_COLUMN``). Damage is reported into ``problems``
    and skipped; memory stays bounded however long the bag."""
    for scan in bag.scans(problems):
        yield from channel_chunks(scan, name, _decode)


def rig_series(bag: str | Path | Bag, topic: str | None = None,
               problems: list[str] | None = None) -> RigSeries:
    """The rig series of ``topic`` (default: the one topic ending in ``joint_states``), all
    in memory (``joint_chunks`` streams it); damage goes into ``problems``."""
    problems = [] if problems is None else problems
    with opened(bag) as b:
        name = joint_topic(b, topic)
        return RigSeries.from_chunks(name, list(joint_chunks(b, name, problems)))


def _decode(rows: np.ndarray) -> JointChunk:
    """Header stamps [ns] and (N, 12) float64 (position[4], velocity[4], effort[4] in the
    order of JOINT_NAMES) from N joint_states messages of one layout."""
    names, offset = joint_state_layout(rows[0].tobytes())
    if tuple(names) != JOINT_NAMES:
        raise BagError(f"joint_states with joints {names}, expected drill_sim's "
                       f"{list(JOINT_NAMES)}")
    stamp = np.ascontiguousarray(rows[:, 4:12]).view("<i4")
    ns = stamp[:, 0].astype(np.int64) * 1_000_000_000 + stamp[:, 1].view("<u4")
    out = np.empty((rows.shape[0], 12))
    f = np.ascontiguousarray(rows[:, offset:offset + 8 * JOINT_VALUES_F64]).view("<f8")
    for k, kind in enumerate(("position", "velocity", "effort")):
        at = JOINT_ARRAY_START[kind]
        out[:, 4 * k:4 * k + 4] = f[:, at:at + 4]
    return ns, out
