"""Writing rosbag2 bags (metadata version 9, MCAP storage) exactly as the real tools read them.

A bag is a directory holding ``metadata.yaml`` and ``<name>_<i>.mcap`` files: profile ``ros2``,
one ``ros2msg`` schema per type (full definition), ``cdr`` channels carrying
``offered_qos_profiles`` and ``topic_type_hash``, zstd chunks. Chunks are closed at least every
``flush_interval_s`` (1 s), so a killed process loses at most that much; ``repair`` restores the
summary and ``metadata.yaml`` afterwards.
"""

from __future__ import annotations

import time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from ..wire.qos import qos_profile
from .errors import BagError
from .mcap_file import McapFileWriter
from .metadata import bag_information, file_entry, write_metadata_yaml
from .schema import message_definition, type_hash

_NS_LIMIT = 1 << 64


# libyaml's emitter when built in (the same text, three times faster): a split writes the
# rosbag2 record on the closing thread, which shares the interpreter with the ticks
_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


def qos_yaml(profiles: list[dict]) -> str:
    return yaml.dump(profiles, Dumper=_DUMPER, sort_keys=False, default_flow_style=False)


@dataclass
class _Topic:
    name: str
    type_name: str
    qos_profiles: list[dict]
    type_hash: str
    count: int = 0
    channel_id: int = -1
    qos_text: str = ""                  # offered_qos_profiles as written in every file


@dataclass
class _File:
    path: Path
    writer: McapFileWriter
    stream: object
    start_ns: int | None = None
    schema_ids: dict[str, int] = field(default_factory=dict)


class BagWriter:
    """Write a rosbag2 MCAP bag into the directory ``path`` (created in an existing folder; must
    not exist).

    split_duration_s / split_size_bytes: start a new ``_<i>.mcap`` file past either (0 = never).
    metadata: name -> {str: str} written as MCAP metadata records in every file.
    """

    def __init__(self, path: str | Path, *, split_duration_s: float = 0.0,
                 split_size_bytes: int = 0, flush_interval_s: float = 1.0,
                 chunk_size: int = 1 << 20, metadata: dict[str, dict[str, str]] | None = None,
                 ros_distro: str = "jazzy") -> None:
        self.path = Path(path)
        if self.path.exists():
            raise BagError(f"bag {self.path}: already exists; choose a new directory")
        try:        # the parent folder must exist: the one rule of every recording entry point
            self.path.mkdir()
        except FileNotFoundError:
            raise BagError(f"bag {self.path}: cannot record there: folder "
                           f"{self.path.absolute().parent} does not exist; expected a new name "
                           "in an existing folder") from None
        except OSError as exc:
            raise BagError(f"bag {self.path}: cannot create it: {exc.strerror}; expected a new "
                           "bag directory in an existing folder") from None
        self.split_duration_ns = int(split_duration_s * 1e9)
        self.split_size_bytes = int(split_size_bytes)
        self.flush_interval_s = flush_interval_s
        self.chunk_size = chunk_size
        self.metadata = dict(metadata or {})
        self.ros_distro = ros_distro
        self.topics: dict[str, _Topic] = {}
        self.files: list[dict] = []
        self._file: _File | None = None
        self._last_flush = time.monotonic()
        self.closed = False
        self._closer = ThreadPoolExecutor(max_workers=1, thread_name_prefix="bag-close")
        self._closing: Future | None = None
        self._open_file()

    # ---- topics and messages -------------------------------------------------------------
    def add_topic(self, name: str, type_name: str, qos: list[dict] | None = None) -> None:
        """Declare a topic (full ROS name, ``pkg/msg/Type``) before writing to it."""
        if name in self.topics:
            return
        profiles = qos or [qos_profile()]
        topic = _Topic(name, type_name, profiles, type_hash(type_name), qos_text=qos_yaml(profiles))
        self.topics[name] = topic
        self._register(topic)

    def write(self, topic: str, data: bytes, log_time_ns: int,
              publish_time_ns: int | None = None) -> None:
        """Append one CDR-serialized message (receive time ``log_time_ns``). Times outside
        0..2^64-1 ns raise ValueError and write nothing."""
        if publish_time_ns is None:
            publish_time_ns = log_time_ns
        if not (0 <= log_time_ns < _NS_LIMIT and 0 <= publish_time_ns < _NS_LIMIT):
            raise ValueError(f"bag {self.path}: {topic}: times {log_time_ns}, "
                             f"{publish_time_ns} ns: expected 0 to 2^64-1")
        t = self.topics[topic]
        f = self._file
        if f is None:
            raise BagError(f"bag {self.path}: already closed")
        if f.start_ns is None:
            f.start_ns = log_time_ns
        elif (self.split_duration_ns and log_time_ns - f.start_ns >= self.split_duration_ns) \
                or (self.split_size_bytes and f.writer.size_bytes >= self.split_size_bytes):
            f = self._split()
            f.start_ns = log_time_ns
        f.writer.add_message(t.channel_id, t.count, log_time_ns, publish_time_ns, data)
        t.count += 1
        now = time.monotonic()
        if now - self._last_flush >= self.flush_interval_s:
            self.flush()
            self._last_flush = now

    def flush(self) -> None:
        """Close the chunk in progress and push it to the disk."""
        self._raise_closing_error()
        if self._file is not None:
            self._file.writer.close_chunk()
            self._file.writer.sync()

    def add_metadata(self, name: str, data: dict[str, str]) -> None:
        """A metadata record written now into the open file (and into any later one): what is
        only known at the end of a recording, such as its losses."""
        self._raise_closing_error()
        self.metadata[name] = dict(data)
        if self._file is not None:
            self._file.writer.add_metadata(name, dict(data))

    def close(self) -> None:
        """Finish the file (summary, indexes) and write ``metadata.yaml``."""
        if self.closed:
            return
        self._closer.shutdown(wait=True)
        self._raise_closing_error()
        self._finish_file()
        write_metadata_yaml(self.path, self._information())
        self.closed = True

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ---- files -------------------------------------------------------------------------
    def _open_file(self) -> None:
        index = len(self.files) + (self._file is not None)
        path = self.path / f"{self.path.name}_{index}.mcap"
        try:
            stream = open(path, "wb")
        except OSError as exc:
            raise BagError(f"bag {self.path}: cannot create {path.name}: {exc.strerror}") \
                from None
        writer = McapFileWriter(stream, profile="ros2", library="drill_sim",
                                chunk_size=self.chunk_size)
        self._file = _File(path, writer, stream)
        for name, data in self.metadata.items():
            writer.add_metadata(name, data)
        for topic in self.topics.values():
            self._register(topic)

    def _register(self, topic: _Topic) -> None:
        f = self._file
        if topic.type_name not in f.schema_ids:
            f.schema_ids[topic.type_name] = f.writer.add_schema(
                topic.type_name, "ros2msg", message_definition(topic.type_name).encode())
        topic.channel_id = f.writer.add_channel(
            topic.name, "cdr", f.schema_ids[topic.type_name],
            {"offered_qos_profiles": topic.qos_text,
             "topic_type_hash": topic.type_hash})

    def _split(self) -> _File:
        """The next file: this one's last chunk goes to its writer now, its summary and footer
        are written on the closing thread (its entry and rosbag2 record are taken here)."""
        f = self._file
        self._raise_closing_error()
        f.writer.close_chunk()
        information = self._information(extra=f)["rosbag2_bagfile_information"]
        self.files.append(self._file_entry(f))
        self._file = None
        try:
            self._open_file()              # first: the closing thread competes for the GIL
        except BagError:                   # no next file: this one still gets its summary
            self._finish_closed(f, information)
            raise
        self._closing = self._closer.submit(self._finish_closed, f, information)
        return self._file

    @staticmethod
    def _finish_closed(f: _File, information: dict) -> None:
        f.writer.add_metadata("rosbag2", {"serialized_metadata": yaml.dump(
            information, Dumper=_DUMPER, sort_keys=False)})
        f.writer.finish()
        f.stream.close()

    def _raise_closing_error(self) -> None:
        """What went wrong finishing an earlier file, raised here (once)."""
        closing, exc = self._closing, None
        if closing is not None and closing.done():
            self._closing, exc = None, closing.exception()
        if exc is not None:
            raise exc

    def _finish_file(self) -> None:
        f = self._file
        if f is None:
            return
        f.writer.close_chunk()
        f.writer.add_metadata("rosbag2", {"serialized_metadata": yaml.safe_dump(
            self._information(extra=f)["rosbag2_bagfile_information"], sort_keys=False)})
        f.writer.finish()
        f.stream.close()
        self.files.append(self._file_entry(f))
        self._file = None

    def _information(self, extra: _File | None = None) -> dict:
        files = self.files + ([self._file_entry(extra)] if extra is not None else [])
        topics = [{"name": t.name, "type": t.type_name, "qos": t.qos_profiles,
                   "hash": t.type_hash, "count": t.count} for t in self.topics.values()]
        custom = {k: str(v) for k, v in self.metadata.get("session", {}).items()}
        return bag_information(topics, files, custom, self.ros_distro)

    @staticmethod
    def _file_entry(f: _File) -> dict:
        w = f.writer
        return file_entry(f.path.name, w.start_time, w.end_time or 0, w.message_count)

