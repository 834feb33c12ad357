"""What ``Bag.info`` reports, and how it is counted: from a file's sound summary (like
``ros2 bag info``) or by walking the file (a crashed or damaged one). Beside the counts, the
span of the header stamps of each ``sensor_msgs/JointState`` topic: the rig's own clock,
simulated time in a sim-time session, where log times are the wall clock."""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from pathlib import Path

from ..wire.rig_topics import JOINT_STATES
from .mcap_scan import MESSAGE_FIELDS, RECORD_HEAD, MappedFile, McapScan
from .mcap_summary import FileSummary, message_index_at

_STAMP = struct.Struct("<iI")                     # a message's header stamp, after CDR's head


@dataclass
class TopicInfo:
    """One topic: its type, message count and recorded publishers' QoS (YAML)."""

    name: str
    type_name: str
    count: int = 0
    offered_qos_profiles: str = ""


@dataclass
class BagInfo:
    """What ``info`` found: topics with counts, time span, metadata records, problems."""

    path: Path
    files: list[Path]
    topics: dict[str, TopicInfo] = field(default_factory=dict)
    start_ns: int | None = None
    end_ns: int | None = None
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    # joint_states topic -> (first, last) header stamp [ns]: the session's own clock
    stamps: dict[str, tuple[int, int]] = field(default_factory=dict)

    @property
    def message_count(self) -> int:
        return sum(t.count for t in self.topics.values())

    @property
    def duration_s(self) -> float:
        return 0.0 if self.start_ns is None else (self.end_ns - self.start_ns) * 1e-9


def count_from_summary(mapped: MappedFile, summary: FileSummary,
                       metadata: dict[str, dict[str, str]], result: BagInfo) -> None:
    """Topics, counts, time span and metadata of a file from its sound summary; the rig's
    header stamps through its chunk indexes (``_stamps_from_index``)."""
    stats = summary.statistics
    for cid, ch in summary.channels.items():
        schema = summary.schemas.get(ch.schema_id)
        topic = result.topics.setdefault(ch.topic, TopicInfo(
            ch.topic, schema.name if schema else "",
            offered_qos_profiles=ch.metadata.get("offered_qos_profiles", "")))
        topic.count += stats.channel_message_counts.get(cid, 0)
        if topic.type_name == JOINT_STATES.type_name:
            _stamps_from_index(mapped, cid, ch.topic, result)
    if stats.message_count:
        _span(result, stats.message_start_time)
        _span(result, stats.message_end_time)
    result.metadata.update(metadata)


def _stamps_from_index(mapped: MappedFile, cid: int, topic: str, result: BagInfo) -> None:
    """The first and last header stamps of channel ``cid``, through the summary's chunk
    indexes (two chunks decompressed)."""
    first = last = None
    for c in [] if mapped.summary is None else mapped.summary.chunk_indexes():
        if cid in c.message_index_offsets:
            first, last = first or c, c
    scan = McapScan(mapped, [])
    for entry, pick in (([first] if first else [], 1), ([last] if last else [], -1)):
        if not entry:
            continue
        found = message_index_at(mapped.view, entry[0].message_index_offsets[cid])
        if found is None or not found[1]:
            continue
        offset = int.from_bytes(found[1][8:16] if pick == 1 else found[1][-8:], "little")
        start = entry[0].chunk_start_offset + RECORD_HEAD.size
        try:
            records = scan.decode_chunk(start, start + entry[0].chunk_length - RECORD_HEAD.size)
            data = offset + RECORD_HEAD.size + MESSAGE_FIELDS.size
            _stamp(result, topic, records[data:data + 12])
        except (ValueError, struct.error):
            continue


def count_by_walking(mapped: MappedFile, result: BagInfo) -> None:
    """Count a file's messages by walking it (CRC-checked chunks, damage skipped and
    reported), and the rig's header stamps on the way."""
    counts: dict[int, int] = {}
    joints: dict[int, bool] = {}
    start = end = None
    scan = McapScan(mapped, result.problems)
    types = scan.channels.types
    for cid, log, _, data in scan.messages():
        counts[cid] = counts.get(cid, 0) + 1
        if start is None or log < start:
            start = log
        if end is None or log > end:
            end = log
        joint = joints.get(cid)
        if joint is None:
            joint = joints[cid] = types.get(cid) == JOINT_STATES.type_name
        if joint:
            _stamp(result, scan.channels.topic(cid), data)
    for cid, ch in scan.channels.records.items():
        topic = result.topics.setdefault(ch.topic, TopicInfo(
            ch.topic, scan.channels.types[cid],
            offered_qos_profiles=ch.metadata.get("offered_qos_profiles", "")))
        topic.count += counts.get(cid, 0)
    result.metadata.update(scan.metadata)
    if start is not None:
        _span(result, start)
        _span(result, end)


def _span(result: BagInfo, t: int) -> None:
    result.start_ns = t if result.start_ns is None else min(result.start_ns, t)
    result.end_ns = t if result.end_ns is None else max(result.end_ns, t)


def _stamp(result: BagInfo, topic: str, data: memoryview) -> None:
    """Widen the topic's header stamp span by the stamp of one CDR message ``data``."""
    if len(data) < 12:
        return
    sec, nsec = _STAMP.unpack_from(data, 4)
    t = sec * 1_000_000_000 + nsec
    first, last = result.stamps.get(topic, (t, t))
    result.stamps[topic] = (min(first, t), max(last, t))
