"""Reading rosbag2 MCAP bags (a bag directory or a bare ``.mcap``), tolerant of damage.

Files are walked record by record (``mcap_scan``: memory-mapped, each chunk's CRC checked), so
a file cut short by a crash yields every message before the cut; what could not be read is
reported in ``BagInfo.problems`` rather than raised. ``info`` takes a sound file's summary
instead of walking it. ``repair`` rewrites a bag whole: summary, indexes and ``metadata.yaml``.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import yaml
from mcap.reader import SeekingReader

from .errors import BagError
from .mcap_file import McapFileWriter
from .mcap_scan import McapScan
from .metadata import bag_information, file_entry


@dataclass(frozen=True)
class BagMessage:
    topic: str
    type_name: str
    data: bytes
    log_time_ns: int
    publish_time_ns: int


@dataclass
class TopicInfo:
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

    @property
    def message_count(self) -> int:
        return sum(t.count for t in self.topics.values())

    @property
    def duration_s(self) -> float:
        return 0.0 if self.start_ns is None else (self.end_ns - self.start_ns) * 1e-9


def mcap_files(path: str | Path) -> list[Path]:
    """The MCAP files of a bag directory (in order) or the bare file itself."""
    path = Path(path)
    if path.is_file():
        return [path]
    if not path.is_dir():
        raise BagError(f"bag {path}: no such file or directory")
    meta = path / "metadata.yaml"
    if meta.is_file():
        try:
            info = yaml.safe_load(meta.read_text(encoding="utf-8"))["rosbag2_bagfile_information"]
            files = [path / p for p in info.get("relative_file_paths", [])]
            if files and all(f.is_file() for f in files):
                return files
        except (yaml.YAMLError, KeyError, TypeError):
            pass                       # a broken metadata.yaml: fall back to the files present
    files = sorted(path.glob("*.mcap"), key=_file_index)
    if not files:
        raise BagError(f"bag {path}: no .mcap file in it")
    return files


def _file_index(p: Path) -> tuple[int, str]:
    stem = p.stem.rsplit("_", 1)
    return (int(stem[1]) if len(stem) == 2 and stem[1].isdigit() else 0, p.name)


def read_messages(path: str | Path, topics: set[str] | None = None,
                  problems: list[str] | None = None) -> Iterator[BagMessage]:
    """Every readable message of the bag in file order (log-time order within a file)."""
    problems = [] if problems is None else problems
    for file in mcap_files(path):
        try:
            scan = McapScan(file, problems)
        except OSError as exc:
            problems.append(f"{file.name}: cannot open: {exc.strerror}")
            continue
        with scan:
            names, types = scan.channels.topics, scan.channels.types
            for cid, log, pub, data in scan.messages():
                topic = names.get(cid, "")
                if topics is None or topic in topics:
                    yield BagMessage(topic, types.get(cid, ""), bytes(data), log, pub)


def topic_types(path: str | Path, problems: list[str] | None = None) -> dict[str, str]:
    """topic -> type of every channel in the bag, from the files' summaries where they have
    one (no message is read), else by skimming the files."""
    problems = [] if problems is None else problems
    found: dict[str, str] = {}
    for file in mcap_files(path):
        summary = _summary(file)
        if summary is not None:
            for ch in summary.channels.values():
                schema = summary.schemas.get(ch.schema_id)
                found.setdefault(ch.topic, schema.name if schema else "")
            continue
        with McapScan(file, problems) as scan:
            for _ in scan.messages(channel_ids=set()):
                pass
            for cid, topic in scan.channels.topics.items():
                found.setdefault(topic, scan.channels.types[cid])
    return found


def _summary(file: Path):
    """The file's summary section, or None if it has none (a crashed file) or it is bad."""
    try:
        with open(file, "rb") as fh:
            return SeekingReader(fh, validate_crcs=True).get_summary()
    except Exception:                   # any damage: the caller reads the file itself
        return None


def info(path: str | Path) -> BagInfo:
    """Topics, counts, time span and metadata records: from each file's summary where it has a
    sound one (like ``ros2 bag info``), else by reading the whole file (a crashed file)."""
    files = mcap_files(path)
    result = BagInfo(Path(path), files)
    for file in files:
        if not _info_from_summary(file, result):
            _info_from_records(file, result)
    return result


def _info_from_summary(file: Path, result: BagInfo) -> bool:
    try:
        with open(file, "rb") as fh:
            reader = SeekingReader(fh, validate_crcs=True)
            summary = reader.get_summary()
            if summary is None or summary.statistics is None:
                return False
            metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
    except Exception:                   # damaged summary: read the records instead
        return False
    stats = summary.statistics
    for cid, ch in summary.channels.items():
        schema = summary.schemas.get(ch.schema_id)
        topic = result.topics.setdefault(ch.topic, TopicInfo(
            ch.topic, schema.name if schema else "",
            offered_qos_profiles=ch.metadata.get("offered_qos_profiles", "")))
        topic.count += stats.channel_message_counts.get(cid, 0)
    if stats.message_count:
        _span(result, stats.message_start_time)
        _span(result, stats.message_end_time)
    result.metadata.update(metadata)
    return True


def _span(result: BagInfo, t: int) -> None:
    result.start_ns = t if result.start_ns is None else min(result.start_ns, t)
    result.end_ns = t if result.end_ns is None else max(result.end_ns, t)


def _info_from_records(file: Path, result: BagInfo) -> None:
    """Count by walking the file (fast path, CRC-checked chunks) up to any damage."""
    counts: dict[int, int] = {}
    start = end = None
    with McapScan(file, result.problems) as scan:
        for cid, log, _, _ in scan.messages():
            counts[cid] = counts.get(cid, 0) + 1
            if start is None or log < start:
                start = log
            if end is None or log > end:
                end = log
        for cid, ch in scan.channels.records.items():
            topic = result.topics.setdefault(ch.topic, TopicInfo(
                ch.topic, scan.channels.types[cid],
                offered_qos_profiles=ch.metadata.get("offered_qos_profiles", "")))
            topic.count += counts.get(cid, 0)
        result.metadata.update(scan.metadata)
    if start is not None:
        _span(result, start)
        _span(result, end)


def repair(path: str | Path) -> BagInfo:
    """Rewrite every file of the bag from what can be read, with summary and indexes, and write
    ``metadata.yaml``. The damaged originals are kept beside as ``*.mcap.damaged``."""
    bag = Path(path)
    if not bag.is_dir():
        raise BagError(f"bag {bag}: repair works on a bag directory")
    entries: list[dict] = []
    topics: dict[str, dict] = {}
    for file in mcap_files(bag):
        damaged = file.with_name(file.name + ".damaged")
        file.replace(damaged)
        entries.append(_rewrite(damaged, file, topics))
    text = yaml.safe_dump(bag_information(list(topics.values()), entries), sort_keys=False)
    (bag / "metadata.yaml").write_text(text, encoding="utf-8")
    return info(bag)


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
