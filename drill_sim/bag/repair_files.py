"""The two things ``repair`` writes: one file rewritten from every readable record of a walk,
and ``metadata.yaml`` made from the summaries of the bag's (now sound) files."""

from __future__ import annotations

import os
from pathlib import Path

import yaml
from mcap.reader import SeekingReader

from .mcap_file import McapFileWriter
from .mcap_scan import MappedFile, McapScan
from .metadata import bag_information, file_entry


def rewrite(scan: McapScan, target: Path, record: dict[str, str]) -> int:
    """Copy every readable message of ``scan``'s file, with its schemas, channels and metadata
    records, into a complete MCAP file ``target`` (synced to disk), plus a ``repair``
    metadata record: ``record`` and what the walk lost. Returns the messages written."""
    schema_ids: dict[int, int] = {}
    channel_ids: dict[int, int] = {}
    sequence: dict[int, int] = {}
    with open(target, "wb") as out:
        writer = McapFileWriter(out, profile="ros2", library="drill_sim repair")
        ch = scan.channels
        for cid, log, pub, data in scan.messages():
            if cid not in channel_ids:
                rec = ch.records.get(cid)
                if rec is None:
                    continue                        # a message of a channel never declared
                schema = ch.schemas.get(rec.schema_id)
                if schema is not None and rec.schema_id not in schema_ids:
                    schema_ids[rec.schema_id] = writer.add_schema(schema.name, schema.encoding,
                                                                  schema.data)
                channel_ids[cid] = writer.add_channel(
                    rec.topic, rec.message_encoding, schema_ids.get(rec.schema_id, 0),
                    dict(rec.metadata))
            writer.add_message(channel_ids[cid], sequence.get(cid, 0), log, pub, bytes(data))
            sequence[cid] = sequence.get(cid, 0) + 1
        writer.close_chunk()
        for name, data in {**_indexed_metadata(scan), **scan.metadata}.items():
            if name not in ("rosbag2", "repair"):
                writer.add_metadata(name, dict(data))
        writer.add_metadata("repair", {**record, "lost": "; ".join(scan.problems) or "nothing",
                                       "gaps": str(scan.gaps)})
        writer.finish()
        out.flush()
        os.fsync(out.fileno())
    return writer.message_count


def _indexed_metadata(scan: McapScan) -> dict[str, dict[str, str]]:
    """The metadata records a sound summary indexes (they may lie in damaged bytes the walk
    skipped)."""
    if scan.summary is None:
        return {}
    try:
        reader = SeekingReader(scan.file.file, validate_crcs=True)
        return {m.name: dict(m.metadata) for m in reader.iter_metadata()}
    except Exception:                              # any damage: the walk's records only
        return {}


def bag_metadata(files: list[Path], old: dict | None) -> dict:
    """metadata.yaml for the bag of ``files`` (each with a sound summary), keeping the old
    one's custom data and ROS distribution."""
    topics: dict[str, dict] = {}
    entries = []
    session: dict[str, str] = {}
    for file in files:
        mapped = MappedFile(file)
        try:
            summary = mapped.summary
            stats = summary.statistics
            for cid, rec in summary.channels.items():
                schema = summary.schemas.get(rec.schema_id)
                topic = topics.setdefault(rec.topic, {
                    "name": rec.topic, "type": schema.name if schema else "",
                    "qos": yaml.safe_load(rec.metadata.get("offered_qos_profiles", "")) or [],
                    "hash": rec.metadata.get("topic_type_hash", ""), "count": 0})
                topic["count"] += stats.channel_message_counts.get(cid, 0)
            entries.append(file_entry(file.name, stats.message_start_time if
                                      stats.message_count else None,
                                      stats.message_end_time, stats.message_count))
            if not session:
                reader = SeekingReader(mapped.file, validate_crcs=True)
                session = next((dict(m.metadata) for m in reader.iter_metadata()
                                if m.name == "session"), {})
        finally:
            mapped.close()
    old = old or {}
    custom = old.get("custom_data") if isinstance(old.get("custom_data"), dict) else session
    return bag_information(list(topics.values()), entries, custom,
                           str(old.get("ros_distro") or "jazzy"))
