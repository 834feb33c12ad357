"""The rig's stamped topics beside its joint_states, streamed and matched by header stamp, for
the bag tools (export, metrics, plot): the top drive's motor torque (``~/top_drive/motor_wrench``)
and what the rig's sensors showed (the stamped ``~/measured/`` topics). Bags recorded before a
topic existed simply have none of it.

Each topic's fields come from the topics table, as columns with SI names: the motor torque as
``motor_torque_nm``; a measured quantity as ``measured_`` + its sample name (e.g.
``measured_surface_torque_nm``). ``~/measured/bit/stick_slip_severity`` is a std_msgs/Float64
with no header, so it cannot be matched by stamp and is not among them.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from ..wire import cdr, rig_topics
from ..wire.rig_topics import RigTopic
from .bag import Bag
from .errors import BagError
from .mcap_index import channel_chunks

MOTOR_COLUMN = "motor_torque_nm"


@dataclass(frozen=True)
class StampedTopic:
    """One stamped topic of the rig and the columns its fields give, with their byte offsets
    in the rig's fixed message layout."""

    topic: RigTopic
    columns: tuple[str, ...]
    offsets: tuple[int, ...]
    stamp_at: int
    size: int

    @classmethod
    def of(cls, name: str, column: Callable[[str], str]) -> StampedTopic:
        t = rig_topics.topic(name)
        lay = cdr.layout(t.type_name, frame_id=t.frame_id)
        return cls(t, tuple(column(f.sample) for f in t.fields),
                   tuple(lay.slots[f.message][0] for f in t.fields), lay.stamps[0], len(lay.buf))

    def decode(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(header stamps [ns], values (rows, columns)) of a chunk's messages."""
        if rows.shape[1] < self.size:
            raise BagError(f"{self.topic.name}: messages of {rows.shape[1]} bytes, expected "
                           f"the rig's {self.size}")
        stamp = np.ascontiguousarray(rows[:, self.stamp_at:self.stamp_at + 8]).view("<i4")
        ns = stamp[:, 0].astype(np.int64) * 1_000_000_000 + stamp[:, 1].view("<u4")
        values = np.column_stack([np.ascontiguousarray(rows[:, at:at + 8]).view("<f8")[:, 0]
                                  for at in self.offsets])
        return ns, values


MOTOR = StampedTopic.of("~/top_drive/motor_wrench", lambda _: MOTOR_COLUMN)
MEASURED = tuple(StampedTopic.of(t.name, lambda sample: "measured_" + sample)
                 for t in rig_topics.TOPICS
                 if t.source == rig_topics.MEASURED and t.type_name in cdr.VECTOR_FIELDS)
STAMPED = (MOTOR, *MEASURED)


def bag_name(bag: Bag, joint_topic: str, spec: StampedTopic) -> str | None:
    """The full name of ``spec``'s topic for the rig whose joint_states are ``joint_topic``,
    or None if the bag has none."""
    suffix = rig_topics.JOINT_STATES.name[1:]                # "/joint_states"
    if not joint_topic.endswith(suffix):
        return None
    name = joint_topic[:-len(suffix)] + spec.topic.name[1:]
    return name if bag.topic_types().get(name) == spec.topic.type_name else None


class StampMatched:
    """A stamped topic's values at the joint_states' stamps, streamed: ``at(ns)`` for each
    increasing array of stamps gives the values stamped the same, one column per field (NaN
    where none), samples sharing a stamp matched in order; memory holds about one chunk.
    Nothing is read before the first ``at``."""

    def __init__(self, chunks: Iterator[tuple[np.ndarray, np.ndarray]], width: int = 1) -> None:
        self._chunks = chunks
        self._ns = np.empty(0, np.int64)
        self._values = np.empty((0, width))
        self._done = False

    def at(self, ns: np.ndarray) -> np.ndarray:
        out = np.full((ns.size, self._values.shape[1]), np.nan)
        if ns.size == 0:
            return out
        last = ns.max()
        # read past ``last``: a stamp shared by two samples (a reset) can end one chunk and
        # begin the next
        while not self._done and (self._ns.size == 0 or self._ns[-1] <= last):
            try:
                more_ns, more = next(self._chunks)
            except StopIteration:
                self._done = True
                break
            self._ns = np.concatenate([self._ns, more_ns])
            self._values = np.concatenate([self._values, np.reshape(more, (more_ns.size, -1))])
        if self._ns.size:
            # the k-th of samples sharing a stamp (a reset publishes the new start at the
            # stamp of the last tick) takes the k-th value of that stamp
            i = np.searchsorted(self._ns, ns)
            first = np.r_[True, ns[1:] != ns[:-1]]
            k = np.arange(ns.size)
            i = np.minimum(i + k - np.maximum.accumulate(np.where(first, k, 0)),
                           self._ns.size - 1)
            hit = self._ns[i] == ns
            out[hit] = self._values[i[hit]]
            # kept for the next read: what is stamped later, and the samples of the last stamp
            # this read did not take (a reset's pair split between two joint_states chunks)
            keep = self._ns > last
            keep[np.flatnonzero(self._ns == last)[np.count_nonzero(ns == last):]] = True
            self._ns, self._values = self._ns[keep], self._values[keep]
        return out


def matched(bag: Bag, joint_topic: str, specs: tuple[StampedTopic, ...] = STAMPED
            ) -> list[tuple[StampedTopic, StampMatched]]:
    """The topics of ``specs`` the bag has for this rig, each ready to match by stamp (damage
    is left to the joint_states walk, which reports it)."""
    out = []
    for spec in specs:
        name = bag_name(bag, joint_topic, spec)
        if name is not None:
            out.append((spec, StampMatched(_chunks(bag, name, spec), len(spec.columns))))
    return out


def _chunks(bag: Bag, name: str, spec: StampedTopic) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    for scan in bag.scans([]):
        yield from channel_chunks(scan, name, spec.decode)
