"""The rig's time series from a bag, decoded without ROS and all at once.

The node's ``~/joint_states`` messages have one fixed layout within a session (same four joint
names, so the same byte length), so their CDR bytes stack into one array and the float fields
are read with a single numpy view: an hour at 1 kHz decodes in a fraction of a second.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..wire.rig_topics import JOINT_NAMES, JOINT_STATES
from .bag import Bag, opened
from .errors import BagError
from .mcap_index import fixed_size_channel

JOINT_STATE = JOINT_STATES.type_name
# where each quantity sits in the node's joint_states (msg_docs/node.md): (array, joint index)
JOINT_FIELDS = {
    "top_drive_speed_rad_s": ("velocity", 0), "surface_torque_nm": ("effort", 0),
    "hook_load_n": ("effort", 1), "bit_depth_m": ("position", 1),
    "bit_speed_rad_s": ("velocity", 2), "tob_nm": ("effort", 2),
    "hole_depth_m": ("position", 3), "rop_m_s": ("velocity", 3), "wob_n": ("effort", 3),
}
# From the position array on, the rig's joint_states is 14 float64 slots: position[4], then a
# uint32 count and 4 bytes of padding (one slot), velocity[4], another slot, effort[4].
JOINT_VALUES_F64 = 14
JOINT_ARRAY_START = {"position": 0, "velocity": 5, "effort": 10}


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

    @property
    def stuck(self) -> np.ndarray:
        """Samples with the bit stuck: not rotating while pressed on the rock."""
        return (self.bit_speed_rad_s == 0.0) & (self.wob_n > 0.0)

    def window(self, start_s: float | None, end_s: float | None) -> RigSeries:
        t = self.time_s - self.time_s[0] if self.time_s.size else self.time_s
        keep = np.ones(t.size, bool)
        if start_s is not None:
            keep &= t >= start_s
        if end_s is not None:
            keep &= t <= end_s
        return RigSeries(self.topic, *(getattr(self, f)[keep] for f in _FIELDS))

    def metrics(self) -> dict[str, float]:
        """MODEL.md section 7 over the samples (each sample weighs the same: a fixed tick)."""
        w = self.bit_speed_rad_s
        if w.size == 0:
            raise BagError(f"{self.topic}: no samples in the window")
        stuck = self.stuck
        mean = float(np.mean(w))
        return {
            "duration_s": float(self.time_s[-1] - self.time_s[0]),
            "samples": int(w.size),
            "ssi": float((w.max() - w.min()) / (2 * mean)) if mean > 0 else float("inf"),
            "stick_fraction": float(np.mean(stuck)),
            "bounce_fraction": float(np.mean(self.wob_n == 0.0)),
            "mean_bit_speed_rad_s": mean,
            "mean_wob_n": float(np.mean(self.wob_n)),
            "mean_tob_nm": float(np.mean(self.tob_nm)),
            "mean_surface_torque_nm": float(np.mean(self.surface_torque_nm)),
            "mean_rop_m_s": float(np.mean(self.rop_m_s)),
        }


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


def rig_series(bag: str | Path | Bag, topic: str | None = None) -> RigSeries:
    """The rig series of ``topic`` (default: the one topic ending in ``joint_states``)."""
    with opened(bag) as b:
        joint_topics = sorted(t for t, kind in b.topic_types().items()
                              if kind == JOINT_STATE and (topic is None or t == topic))
        if not joint_topics:
            raise BagError(f"bag {b.path}: no {JOINT_STATE} topic"
                           f"{'' if topic is None else ' ' + topic} to read the rig from")
        if len(joint_topics) > 1:
            raise BagError(f"bag {b.path}: several joint_states topics "
                           f"({', '.join(joint_topics)}); choose one with --topic")
        name = joint_topics[0]
        parts = []
        for scan in b.scans([]):
            values = fixed_size_channel(scan, name, _decode)
            if values is None:                  # no index or sizes differ: message by message
                names = scan.channels.topics
                datas = [bytes(d) for cid, _, _, d in scan.messages() if names.get(cid) == name]
                same = [d for d in datas if len(d) == len(datas[0])]
                values = _decode(np.frombuffer(b"".join(same), np.uint8).reshape(
                    len(same), -1)) if same else None
            if values is not None and values.size:
                parts.append(values)
    if not parts:
        raise BagError(f"{name}: no message in the bag")
    v = np.concatenate(parts)
    return RigSeries.from_joints(name, v[:, 0], v[:, 1:5], v[:, 5:9], v[:, 9:13])


def _decode(rows: np.ndarray) -> np.ndarray:
    """(N, 13) float64 from N joint_states messages of one layout: stamp [s], position[4],
    velocity[4], effort[4] in the order of JOINT_NAMES."""
    names, offset = joint_state_layout(rows[0].tobytes())
    if tuple(names) != JOINT_NAMES:
        raise BagError(f"joint_states with joints {names}, expected drill_sim's "
                       f"{list(JOINT_NAMES)}")
    stamp = np.ascontiguousarray(rows[:, 4:12]).view("<i4")
    out = np.empty((rows.shape[0], 13))
    out[:, 0] = stamp[:, 0] + 1e-9 * stamp[:, 1].view("<u4")
    f = np.ascontiguousarray(rows[:, offset:offset + 8 * JOINT_VALUES_F64]).view("<f8")
    for k, kind in enumerate(("position", "velocity", "effort")):
        at = JOINT_ARRAY_START[kind]
        out[:, 1 + 4 * k:5 + 4 * k] = f[:, at:at + 4]
    return out
