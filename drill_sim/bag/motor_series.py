"""The top drive's motor torque from a rig bag (``~/top_drive/motor_wrench``), streamed beside
the rig's joint_states and matched to them by header stamp, for the bag tools (export, metrics,
plot). Bags recorded before the topic existed simply have none."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from ..wire import cdr, rig_topics
from .bag import Bag
from .errors import BagError
from .mcap_index import channel_chunks

MOTOR_WRENCH = rig_topics.topic("~/top_drive/motor_wrench")
COLUMN = "motor_torque_nm"                                # its SI name in the tools' output
_LAYOUT = cdr.layout(MOTOR_WRENCH.type_name, frame_id=MOTOR_WRENCH.frame_id)
_TORQUE_AT = _LAYOUT.slots["wrench.torque.z"][0]
_STAMP_AT = _LAYOUT.stamps[0]


def motor_topic(bag: Bag, joint_topic: str) -> str | None:
    """The motor torque topic of the rig whose joint_states are ``joint_topic``, or None if
    the bag has none."""
    suffix = rig_topics.JOINT_STATES.name[1:]                # "/joint_states"
    if not joint_topic.endswith(suffix):
        return None
    name = joint_topic[:-len(suffix)] + MOTOR_WRENCH.name[1:]
    return name if bag.topic_types().get(name) == MOTOR_WRENCH.type_name else None


def _decode(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if rows.shape[1] < _TORQUE_AT + 8:
        raise BagError(f"{MOTOR_WRENCH.name}: messages of {rows.shape[1]} bytes, expected "
                       f"the rig's {len(_LAYOUT.buf)}")
    stamp = np.ascontiguousarray(rows[:, _STAMP_AT:_STAMP_AT + 8]).view("<i4")
    ns = stamp[:, 0].astype(np.int64) * 1_000_000_000 + stamp[:, 1].view("<u4")
    torque = np.ascontiguousarray(rows[:, _TORQUE_AT:_TORQUE_AT + 8]).view("<f8")[:, 0]
    return ns, torque


def motor_chunks(bag: Bag, name: str) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Header stamps [ns] and motor torques [N m], a chunk at a time (damage is left to the
    joint_states walk, which reports it)."""
    for scan in bag.scans([]):
        yield from channel_chunks(scan, name, _decode)


class StampMatched:
    """A second topic's values at the joint_states' stamps, streamed: ``at(ns)`` for each
    increasing array of stamps gives the values stamped the same (NaN where none); memory
    holds about one chunk."""

    def __init__(self, chunks: Iterator[tuple[np.ndarray, np.ndarray]]) -> None:
        self._chunks = chunks
        self._ns = np.empty(0, np.int64)
        self._values = np.empty(0)
        self._done = False

    def at(self, ns: np.ndarray) -> np.ndarray:
        out = np.full(ns.size, np.nan)
        if ns.size == 0:
            return out
        last = ns.max()
        while not self._done and (self._ns.size == 0 or self._ns[-1] < last):
            try:
                more_ns, more = next(self._chunks)
            except StopIteration:
                self._done = True
                break
            self._ns = np.concatenate([self._ns, more_ns])
            self._values = np.concatenate([self._values, more])
        if self._ns.size:
            i = np.minimum(np.searchsorted(self._ns, ns), self._ns.size - 1)
            hit = self._ns[i] == ns
            out[hit] = self._values[i[hit]]
            keep = self._ns > last
            self._ns, self._values = self._ns[keep], self._values[keep]
        return out
