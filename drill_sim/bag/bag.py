"""A rosbag2 MCAP bag (a bag directory or a bare ``.mcap``) opened once for every reader.

The tools ask a bag several things in turn (its topics and types, then the messages; its
info and metadata, then the messages), so ``Bag`` opens and memory-maps each file once, on
first use, and keeps it until closed: summaries, metadata records, channels and any number of
walks share it. Files are walked record by record (``mcap_scan``: each chunk's CRC checked),
so a file cut short by a crash yields every message before the cut; what could not be read
is reported in ``problems`` rather than raised. ``info`` takes a sound file's summary instead
of walking it, like ``ros2 bag info``.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from mcap.reader import SeekingReader
from mcap.summary import Summary

from .errors import BagError
from .mcap_scan import MappedFile, McapScan
from .metadata import read_metadata_yaml


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


@dataclass
class _Summary:
    """A file's summary section and metadata records; None where absent or damaged."""

    summary: Summary | None
    metadata: dict[str, dict[str, str]] | None


class Bag:
    """One bag, opened with ``Bag.open``; use as a context manager (or call ``close``).

    ``files``: the MCAP files in order; ``metadata_yaml``: the ``rosbag2_bagfile_information``
    of its metadata.yaml (None for a bare file or a missing or broken one).
    """

    def __init__(self, path: Path, files: list[Path], metadata_yaml: dict | None) -> None:
        self.path, self.files, self.metadata_yaml = path, files, metadata_yaml
        self._mapped: dict[Path, MappedFile] = {}
        self._summaries: dict[Path, _Summary] = {}
        self._info: BagInfo | None = None

    @classmethod
    def open(cls, path: str | Path) -> Bag:
        """The bag at ``path``: its files listed (from metadata.yaml where it names files that
        exist, else the ``*.mcap`` present, by index); none is opened yet."""
        path = Path(path)
        if path.is_file():
            return cls(path, [path], None)
        if not path.is_dir():
            raise BagError(f"bag {path}: no such file or directory")
        meta = read_metadata_yaml(path)
        try:
            files = [path / p for p in (meta or {}).get("relative_file_paths", [])]
        except TypeError:
            files = []                         # a broken metadata.yaml: take the files present
        if not files or not all(f.is_file() for f in files):
            files = sorted(path.glob("*.mcap"), key=_file_index)
        if not files:
            raise BagError(f"bag {path}: no .mcap file in it")
        return cls(path, files, meta)

    def close(self) -> None:
        for mapped in self._mapped.values():
            mapped.close()
        self._mapped.clear()

    def __enter__(self) -> Bag:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ---- files ---------------------------------------------------------------------------
    def mapped(self, file: Path) -> MappedFile:
        """``file`` opened and memory-mapped, the first time it is asked for (OSError if it
        cannot be opened)."""
        if file not in self._mapped:
            self._mapped[file] = MappedFile(file)
        return self._mapped[file]

    def scans(self, problems: list[str]) -> Iterator[McapScan]:
        """A fresh walk over each file in order, damage reported into ``problems`` (OSError
        for a file that cannot be opened)."""
        for file in self.files:
            yield McapScan(self.mapped(file), problems)

    def summary(self, file: Path) -> Summary | None:
        """The file's summary section, or None if it has none (a crashed file) or it is bad."""
        return self._summary(file).summary

    def _summary(self, file: Path) -> _Summary:
        if file not in self._summaries:
            found = _Summary(None, None)
            try:
                reader = SeekingReader(self.mapped(file).file, validate_crcs=True)
                found.summary = reader.get_summary()
                if found.summary is not None and found.summary.statistics is not None:
                    found.metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
            except Exception:               # any damage: the caller reads the file itself
                pass
            self._summaries[file] = found
        return self._summaries[file]

    # ---- what the bag holds --------------------------------------------------------------
    def info(self) -> BagInfo:
        """Topics, counts, time span and metadata records: from each file's summary where it
        has a sound one, else by reading the whole file (a crashed file). Worked out once."""
        if self._info is None:
            result = BagInfo(self.path, list(self.files))
            for file in self.files:
                self.mapped(file)                   # one that cannot be opened: OSError
                if not self._info_from_summary(file, result):
                    self._info_from_records(file, result)
            self._info = result
        return self._info

    @property
    def metadata(self) -> dict[str, dict[str, str]]:
        """The MCAP metadata records (name -> {key: value}) of all files."""
        return self.info().metadata

    def topic_types(self, problems: list[str] | None = None) -> dict[str, str]:
        """topic -> type of every channel, from the files' summaries where they have one (no
        message is read), else by skimming the files (or from ``info`` if already known)."""
        if self._info is not None:
            return {t.name: t.type_name for t in self._info.topics.values()}
        problems = [] if problems is None else problems
        found: dict[str, str] = {}
        for file in self.files:
            summary = self.summary(file)
            if summary is not None:
                for ch in summary.channels.values():
                    schema = summary.schemas.get(ch.schema_id)
                    found.setdefault(ch.topic, schema.name if schema else "")
                continue
            scan = McapScan(self.mapped(file), problems)
            for _ in scan.messages(channel_ids=set()):
                pass
            for cid, topic in scan.channels.topics.items():
                found.setdefault(topic, scan.channels.types[cid])
        return found

    def messages(self, topics: set[str] | None = None, problems: list[str] | None = None
                 ) -> Iterator[BagMessage]:
        """Every readable message (of ``topics`` if given) in file order, log-time order
        within a file; a file that cannot be opened is a problem, not an error."""
        problems = [] if problems is None else problems
        for file in self.files:
            try:
                scan = McapScan(self.mapped(file), problems)
            except OSError as exc:
                problems.append(f"{file.name}: cannot open: {exc.strerror}")
                continue
            names, types = scan.channels.topics, scan.channels.types
            for cid, log, pub, data in scan.messages():
                topic = names.get(cid, "")
                if topics is None or topic in topics:
                    yield BagMessage(topic, types.get(cid, ""), bytes(data), log, pub)

    def _info_from_summary(self, file: Path, result: BagInfo) -> bool:
        found = self._summary(file)
        summary = found.summary
        if summary is None or summary.statistics is None or found.metadata is None:
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
        result.metadata.update(found.metadata)
        return True

    def _info_from_records(self, file: Path, result: BagInfo) -> None:
        """Count by walking the file (fast path, CRC-checked chunks) up to any damage."""
        counts: dict[int, int] = {}
        start = end = None
        scan = McapScan(self.mapped(file), result.problems)
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


@contextlib.contextmanager
def opened(bag: str | Path | Bag) -> Iterator[Bag]:
    """``bag`` itself if already open (left open), else the bag at that path, closed after."""
    if isinstance(bag, Bag):
        yield bag
        return
    with Bag.open(bag) as b:
        yield b


def _span(result: BagInfo, t: int) -> None:
    result.start_ns = t if result.start_ns is None else min(result.start_ns, t)
    result.end_ns = t if result.end_ns is None else max(result.end_ns, t)


def _file_index(p: Path) -> tuple[int, str]:
    stem = p.stem.rsplit("_", 1)
    return (int(stem[1]) if len(stem) == 2 and stem[1].isdigit() else 0, p.name)
