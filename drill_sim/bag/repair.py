"""Repairing a bag cut short by a crash: every file rewritten whole from what can be read
(summary, indexes, statistics) and ``metadata.yaml`` written, so seeking readers
(``ros2 bag play``, Foxglove) open it again. The damaged originals are kept beside."""

from __future__ import annotations

from pathlib import Path

import yaml

from .bag import Bag, BagInfo
from .errors import BagError
from .mcap_file import McapFileWriter
from .mcap_scan import McapScan
from .metadata import bag_information, file_entry, write_metadata_yaml


def repair(path: str | Path) -> BagInfo:
    """Rewrite every file of the bag from what can be read, with summary and indexes, and write
    ``metadata.yaml``. The damaged originals are kept beside as ``*.mcap.damaged``. Returns
    the info of the repaired bag."""
    bag = Path(path)
    if not bag.is_dir():
        raise BagError(f"bag {bag}: repair works on a bag directory")
    with Bag.open(bag) as listed:                  # only listed: each is moved aside first
        files = listed.files
    entries: list[dict] = []
    topics: dict[str, dict] = {}
    for file in files:
        damaged = file.with_name(file.name + ".damaged")
        file.replace(damaged)
        entries.append(_rewrite(damaged, file, topics))
    write_metadata_yaml(bag, bag_information(list(topics.values()), entries))
    with Bag.open(bag) as repaired:
        return repaired.info()


def _rewrite(source: Path, target: Path, topics: dict[str, dict]) -> dict:
    """Copy every readable record of ``source`` into a complete MCAP file ``target``; count
    messages per topic into ``topics``; return the file's metadata.yaml entry."""
    schema_ids: dict[int, int] = {}
    channel_ids: dict[int, tuple[int, str]] = {}
    sequence: dict[int, int] = {}
    with open(target, "wb") as out, McapScan(source, []) as scan:
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
                channel_ids[cid] = (writer.add_channel(
                    rec.topic, rec.message_encoding, schema_ids.get(rec.schema_id, 0),
                    dict(rec.metadata)), rec.topic)
                topics.setdefault(rec.topic, {
                    "name": rec.topic, "type": ch.types.get(cid, ""),
                    "qos": yaml.safe_load(rec.metadata.get("offered_qos_profiles", "")) or [],
                    "hash": rec.metadata.get("topic_type_hash", ""), "count": 0})
            new_id, topic = channel_ids[cid]
            writer.add_message(new_id, sequence.get(cid, 0), log, pub, bytes(data))
            sequence[cid] = sequence.get(cid, 0) + 1
            topics[topic]["count"] += 1
        writer.close_chunk()
        for name, data in scan.metadata.items():
            if name != "rosbag2":
                writer.add_metadata(name, data)
        writer.finish()
    return file_entry(target.name, writer.start_time, writer.end_time or 0,
                      writer.message_count)
