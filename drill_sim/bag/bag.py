"""A rosbag2 MCAP bag (a bag directory or a bare ``.mcap``) opened once for every reader.

The tools ask a bag several things in turn (its topics and types, then the messages; its
info and metadata, then the messages), so ``Bag`` opens and memory-maps each file once, on
first use, and keeps it until closed: summaries, metadata records, channels and any number of
walks share it. Files are walked record by record (``mcap_scan``: each chunk's CRC checked,
damaged parts skipped), so a damaged file yields every intact chunk and a file cut short by a
crash every message before the cut; what could not be read is reported in ``problems`` (data
lost: a result over it is partial) rather than raised, and what is odd but loses nothing (a
file listed twice, no metadata.yaml) in ``notes``. ``info`` takes a file's summary instead of
counting its messages, like ``ros2 bag info``, once every chunk has passed its CRC check.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from .bag_info import BagInfo, TopicInfo, count_by_walking, count_from_summary
from .errors import BagError
from .mcap_scan import MAGIC, MappedFile, McapScan, what_it_is
from .mcap_summary import FileSummary
from .metadata import read_metadata_yaml
from .verify import damage

__all__ = ["Bag", "BagInfo", "BagMessage", "TopicInfo", "opened"]


@dataclass(frozen=True)
class BagMessage:
    topic: str
    type_name: str
    data: bytes
    log_time_ns: int
    publish_time_ns: int


@dataclass
class _Summary:
    """A file's summary section and metadata records; None where absent or damaged."""

    summary: FileSummary | None
    metadata: dict[str, dict[str, str]] | None


class Bag:
    """One bag, opened with ``Bag.open``; use as a context manager (or call ``close``).

    ``files``: the MCAP files in order; ``metadata_yaml``: the ``rosbag2_bagfile_information``
    of its metadata.yaml (None for a bare file or a missing or broken one).
    """

    def __init__(self, path: Path, files: list[Path], metadata_yaml: dict | None,
                 notes: list[str] | None = None) -> None:
        self.path, self.files, self.metadata_yaml = path, files, metadata_yaml
        self.notes = list(notes or [])
        self._mapped: dict[Path, MappedFile] = {}
        self._summaries: dict[Path, _Summary] = {}
        self._info: BagInfo | None = None
        self._verified = False

    @classmethod
    def open(cls, path: str | Path) -> Bag:
        """The bag at ``path``: its files listed (from metadata.yaml where it names files that
        exist, each once, else the ``*.mcap`` present, by index); none is opened yet."""
        path = Path(path)
        if path.is_file():
            try:
                with path.open("rb") as f:
                    head = f.read(16)                  # enough to say what it is, if not MCAP
            except OSError as exc:
                raise BagError(f"{path}: cannot be read ({exc.strerror})") from None
            if head[:len(MAGIC)] != MAGIC:     # every tool says the same of a file that is not
                raise BagError(f"{path}: not an MCAP file ({what_it_is(memoryview(head))})")
            return cls(path, [path], None)
        if path.exists() and not path.is_dir():
            raise BagError(f"bag {path}: not a file or a folder (a device, a pipe or a socket); "
                           "expected an MCAP file or a bag folder")
        if not path.is_dir():
            raise BagError(f"bag {path}: no such file or directory")
        meta = read_metadata_yaml(path)
        notes = [] if meta is not None else [
            "no readable metadata.yaml (a crashed recording has none; repair writes it)"]
        try:
            listed = [path / p for p in (meta or {}).get("relative_file_paths", [])]
        except TypeError:
            listed = []                        # a broken metadata.yaml: take the files present
        files = list(dict.fromkeys(listed))
        for f in files:
            if listed.count(f) > 1:
                notes.append(f"metadata.yaml lists {f.name} {listed.count(f)} times; "
                             "it is read once")
        if not files or not all(f.is_file() for f in files):
            files = sorted(path.glob("*.mcap"), key=_file_index)
        if not files:
            raise BagError(f"bag {path}: no .mcap file in it")
        return cls(path, files, meta, notes)

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

    def summary(self, file: Path) -> FileSummary | None:
        """The file's summary section, or None if it has none (a crashed file) or it is bad."""
        return self._summary(file).summary

    def _summary(self, file: Path) -> _Summary:
        if file not in self._summaries:
            found = _Summary(None, None)
            try:
                found.summary = self.mapped(file).summary
                if found.summary is not None and found.summary.statistics is not None:
                    found.metadata = found.summary.metadata()
            except (OSError, ValueError):       # any damage: the caller reads the file itself
                pass
            self._summaries[file] = found
        return self._summaries[file]

    # ---- what the bag holds --------------------------------------------------------------
    def info(self, verify: bool = True) -> BagInfo:
        """Topics, counts, time span, metadata records and header stamps: from each file's
        summary where it has a sound one (with ``verify``, only once every chunk has passed
        its CRC check: ``verify.damage``), else by reading the whole file (a crashed or
        damaged file). BagError if no file is MCAP. Worked out once."""
        if self._info is None or (verify and not self._verified):
            result = BagInfo(self.path, list(self.files), notes=list(self.notes))
            foreign = []
            for file in self.files:
                mapped = self.mapped(file)          # one that cannot be opened: OSError
                if not mapped.is_mcap:
                    foreign.append(f"{file.name}: not an MCAP file ({what_it_is(mapped.view)})")
                elif not self._from_summary(file, result, verify):
                    count_by_walking(mapped, result)
            if len(foreign) == len(self.files):
                raise BagError(f"{self.path}: {foreign[0].split(': ', 1)[1]}"
                               if self.path.is_file() else f"bag {self.path}: {foreign[0]}")
            result.problems[:0] = foreign
            repaired, notes = self.repaired()
            result.problems += repaired
            result.notes += notes
            self._info, self._verified = result, verify
        return self._info

    def repaired(self) -> tuple[list[str], list[str]]:
        """What earlier repairs recorded (their ``repair`` metadata records) as (problems,
        notes): a repair that skipped damaged data with intact data after it left a gap, a
        problem of the bag; one that only lost the end of a crashed recording, a note."""
        problems: list[str] = []
        notes: list[str] = []
        for file in self.files:
            record = (self._summary(file).metadata or {}).get("repair")
            if record is None or record.get("lost", "nothing") == "nothing":
                continue
            text = (f"{file.name} was repaired ({record.get('date', '?')}; the original is "
                    f"kept as {record.get('original', '?')}), and lost: {record['lost']}")
            (problems if record.get("gaps", "0") != "0" else notes).append(text)
        return problems, notes

    def _from_summary(self, file: Path, result: BagInfo, verify: bool) -> bool:
        """``count_from_summary`` if the file has a sound summary (and, with ``verify``,
        every chunk passes its CRC check)."""
        found = self._summary(file)
        if found.summary is None or found.summary.statistics is None or found.metadata is None:
            return False
        if verify and damage(self.mapped(file)):
            return False                            # counted by walking, damage reported
        count_from_summary(self.mapped(file), found.summary, found.metadata, result)
        return True

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

@contextlib.contextmanager
def opened(bag: str | Path | Bag) -> Iterator[Bag]:
    """``bag`` itself if already open (left open), else the bag at that path, closed after."""
    if isinstance(bag, Bag):
        yield bag
        return
    with Bag.open(bag) as b:
        yield b


def _file_index(p: Path) -> tuple[int, str]:
    stem = p.stem.rsplit("_", 1)
    return (int(stem[1]) if len(stem) == 2 and stem[1].isdigit() else 0, p.name)
