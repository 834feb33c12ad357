"""Reading an MCAP file's messages fast: the file is memory-mapped and walked record by record
with ``struct``, chunks are decompressed whole, and one channel of fixed-size messages can be
cut out of every chunk at once with numpy through the message indexes.

``mcap.stream_reader`` builds an object per record (~12 us a message); this walk takes about
1 us a message, and the numpy path a few ns, which is what replay at speed and an hour of
1 kHz data need. Damage ends the walk and is reported in ``problems``; everything before it
is delivered. Each chunk's CRC is checked, so damaged bytes are found, not decoded.
"""

from __future__ import annotations

import mmap
import struct
import zlib
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import zstandard
from numpy.lib.stride_tricks import as_strided

OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK, OP_MESSAGE_INDEX = 0x03, 0x04, 0x05, 0x06, 0x07
OP_FOOTER, OP_METADATA = 0x02, 0x0C
MAGIC = b"\x89MCAP0\r\n"
_RECORD = struct.Struct("<BQ")
_MESSAGE = struct.Struct("<HIQQ")
_CHUNK = struct.Struct("<QQQI")
_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")
_MESSAGE_HEAD = 1 + 8 + _MESSAGE.size              # opcode, length, fixed message fields


@dataclass(frozen=True)
class SchemaRecord:
    id: int
    name: str
    encoding: str
    data: bytes


@dataclass(frozen=True)
class ChannelRecord:
    id: int
    schema_id: int
    topic: str
    message_encoding: str
    metadata: dict[str, str]


@dataclass
class Channels:
    """Schemas and channels seen so far: id -> topic and id -> type name, and the records."""

    schemas: dict[int, SchemaRecord] = field(default_factory=dict)
    records: dict[int, ChannelRecord] = field(default_factory=dict)
    topics: dict[int, str] = field(default_factory=dict)
    types: dict[int, str] = field(default_factory=dict)

    def read_schema(self, body: memoryview) -> None:
        (sid,) = _U16.unpack_from(body, 0)
        name, pos = _string(body, 2)
        encoding, pos = _string(body, pos)
        (n,) = _U32.unpack_from(body, pos)
        if pos + 4 + n > len(body):
            raise ValueError(f"schema {name!r} longer than its record")
        self.schemas[sid] = SchemaRecord(sid, name, encoding, bytes(body[pos + 4:pos + 4 + n]))

    def read_channel(self, body: memoryview) -> None:
        cid, sid = struct.unpack_from("<HH", body, 0)
        topic, pos = _string(body, 4)
        encoding, pos = _string(body, pos)
        meta = _map(body, pos)[0]
        self.records[cid] = ChannelRecord(cid, sid, topic, encoding, meta)
        self.topics[cid] = topic
        schema = self.schemas.get(sid)
        self.types[cid] = schema.name if schema else ""


def _map(buf: memoryview, pos: int) -> tuple[dict[str, str], int]:
    (length,) = _U32.unpack_from(buf, pos)
    pos += 4
    end = pos + length
    if end > len(buf):
        raise ValueError("map longer than its record")
    out = {}
    while pos < end:
        key, pos = _string(buf, pos)
        out[key], pos = _string(buf, pos)
    return out, pos


def _string(buf: memoryview, pos: int) -> tuple[str, int]:
    (n,) = _U32.unpack_from(buf, pos)
    if pos + 4 + n > len(buf):
        raise ValueError("string longer than its record")
    return bytes(buf[pos + 4:pos + 4 + n]).decode("utf-8", "replace"), pos + 4 + n


class McapScan:
    """One MCAP file, memory-mapped. Use as a context manager."""

    def __init__(self, path: str | Path, problems: list[str]) -> None:
        self.path = Path(path)
        self.problems = problems
        self.channels = Channels()
        self.metadata: dict[str, dict[str, str]] = {}     # metadata records met on the walk
        self._file = open(self.path, "rb")
        size = self.path.stat().st_size
        self.data = mmap.mmap(self._file.fileno(), 0, access=mmap.ACCESS_READ) if size \
            else b""
        self.view = memoryview(self.data)
        self._decompress = zstandard.ZstdDecompressor().decompress

    def __enter__(self) -> McapScan:
        return self

    def __exit__(self, *exc) -> None:
        self._file.close()
        try:
            self.view.release()
            if isinstance(self.data, mmap.mmap):
                self.data.close()
        except BufferError:
            pass                # views handed out still live; the map goes with the last one

    def _problem(self, where: int, what: str) -> None:
        self.problems.append(f"{self.path.name}: unreadable from about byte {where} of "
                             f"{len(self.data)} ({what}); everything before was read")

    def records(self) -> Iterator[tuple[int, int, int]]:
        """Top-level records as (opcode, body start, body end), stopping at damage."""
        data, size = self.view, len(self.data)
        if bytes(data[:8]) != MAGIC:
            self._problem(0, "not an MCAP file: bad magic")
            return
        pos = 8
        while pos < size:
            if pos + 9 > size:
                self._problem(pos, "cut short inside a record header")
                return
            op, length = _RECORD.unpack_from(data, pos)
            start, end = pos + 9, pos + 9 + length
            if end > size:
                self._problem(pos, f"cut short: record of {length} bytes")
                return
            if op == OP_FOOTER:
                return
            yield op, start, end
            pos = end

    def chunk_records(self, start: int, end: int, decompressor=None) -> memoryview | None:
        """The decompressed records of the chunk whose body is [start, end) (pass a
        decompressor of its own from another thread)."""
        v = self.view
        _, _, size, crc = _CHUNK.unpack_from(v, start)
        compression, pos = _string(v, start + _CHUNK.size)
        (n,) = _U64.unpack_from(v, pos)
        pos += 8
        if pos + n > end:
            self._problem(start, "chunk longer than its record")
            return None
        payload = v[pos:pos + n]
        try:
            if compression == "zstd":
                decompress = self._decompress if decompressor is None \
                    else decompressor.decompress
                records = memoryview(decompress(payload, max_output_size=size))
            elif compression == "":
                records = payload
            elif compression == "lz4":
                import lz4.frame
                records = memoryview(lz4.frame.decompress(bytes(payload)))
            else:
                self._problem(start, f"unknown chunk compression '{compression}'")
                return None
        except Exception as exc:                        # zstd/lz4 errors on damaged data
            self._problem(start, f"chunk does not decompress: {exc}")
            return None
        if crc and zlib.crc32(records) != crc:
            self._problem(start, "chunk fails its CRC check")
            return None
        return records

    def messages(self, channel_ids: set[int] | None = None
                 ) -> Iterator[tuple[int, int, int, memoryview]]:
        """(channel id, log time, publish time, data) of every message in file order; schemas
        and channels are collected into ``self.channels`` on the way."""
        ch = self.channels
        start = 0
        try:
            for op, start, end in self.records():
                if op == OP_CHUNK:
                    records = self.chunk_records(start, end)
                    if records is None:
                        return
                    yield from self._inner(records, channel_ids)
                elif op == OP_MESSAGE:
                    cid, _, log, pub = _MESSAGE.unpack_from(self.view, start)
                    if channel_ids is None or cid in channel_ids:
                        yield cid, log, pub, self.view[start + _MESSAGE.size:end]
                elif op == OP_SCHEMA:
                    ch.read_schema(self.view[start:end])
                elif op == OP_CHANNEL:
                    ch.read_channel(self.view[start:end])
                elif op == OP_METADATA:
                    name, pos = _string(self.view, start)
                    self.metadata[name] = _map(self.view, pos)[0]
        except (struct.error, ValueError) as exc:       # a record that contradicts itself
            self._problem(start, f"bad record: {exc}")

    def _inner(self, records: memoryview, channel_ids: set[int] | None
               ) -> Iterator[tuple[int, int, int, memoryview]]:
        pos, size = 0, len(records)
        unpack_record, unpack_message = _RECORD.unpack_from, _MESSAGE.unpack_from
        while pos + 9 <= size:
            op, length = unpack_record(records, pos)
            start = pos + 9
            pos = start + length
            if pos > size:
                raise ValueError(f"record of {length} bytes at {start - 9} of {size}")
            if op == OP_MESSAGE:
                cid, _, log, pub = unpack_message(records, start)
                if channel_ids is None or cid in channel_ids:
                    yield cid, log, pub, records[start + _MESSAGE.size:pos]
            elif op == OP_SCHEMA:
                self.channels.read_schema(records[start:pos])
            elif op == OP_CHANNEL:
                self.channels.read_channel(records[start:pos])

    def fixed_size_channel(self, topic: str, convert: Callable[[np.ndarray], np.ndarray],
                           workers: int = 2) -> np.ndarray | None:
        """Every message of ``topic``, cut out of each chunk at once through the message index
        that follows it as rows of bytes, passed through ``convert`` (rows -> 2-D array) and
        stacked. Chunks are decompressed, cut and converted on ``workers`` threads (zstd and
        numpy let go of the GIL). None if the topic's messages differ in size or a chunk has
        no index: the caller then walks the messages."""
        try:
            jobs = self._index_jobs(topic)
        except (struct.error, ValueError):
            return None                                  # damaged: the walk reports where
        if jobs is None:
            return None

        def job(chunk_start: int, chunk_end: int, pairs: np.ndarray) -> np.ndarray | None:
            try:
                records = self.chunk_records(chunk_start, chunk_end,
                                             zstandard.ZstdDecompressor())
            except (struct.error, ValueError):
                return None                              # a damaged chunk header
            rows = None if records is None else _cut(np.frombuffer(records, np.uint8),
                                                     pairs[:, 1])
            return None if rows is None else (rows.shape[1], convert(rows))

        with ThreadPoolExecutor(max_workers=workers) as pool:
            parts = list(pool.map(lambda j: job(*j), jobs))
        if any(p is None for p in parts) or len({size for size, _ in parts}) > 1:
            return None
        return np.concatenate([a for _, a in parts]) if parts else None

    def _index_jobs(self, topic: str) -> list[tuple[int, int, np.ndarray]] | None:
        """(chunk body start, end, message index pairs of ``topic``) for every chunk, or None
        if a chunk has no index or messages lie outside chunks."""
        jobs: list[tuple[int, int, np.ndarray]] = []
        chunk: tuple[int, int] | None = None
        target: int | None = None
        unindexed = False                    # a chunk with no message index after it
        for op, start, end in self.records():
            v = self.view
            if op == OP_CHUNK:
                if unindexed:
                    return None
                chunk, unindexed = (start, end), True
                if target is None:                      # channel records live in the chunks
                    records = self.chunk_records(start, end)
                    if records is None:
                        break
                    for _ in self._inner(records, set()):
                        pass
                    target = next((c for c, t in self.channels.topics.items() if t == topic),
                                  None)
            elif op == OP_MESSAGE_INDEX and chunk is not None:
                unindexed = False
                (cid,) = _U16.unpack_from(v, start)
                if cid == target:
                    (n,) = _U32.unpack_from(v, start + 2)
                    jobs.append((*chunk, np.frombuffer(v[start + 6:start + 6 + n],
                                                       dtype="<u8").reshape(-1, 2)))
            elif op == OP_MESSAGE:
                return None                              # messages outside chunks: walk them
            elif op == OP_CHANNEL:
                self.channels.read_channel(v[start:end])
            elif op == OP_SCHEMA:
                self.channels.read_schema(v[start:end])
        return None if unindexed else jobs


def _cut(chunk: np.ndarray, offsets: np.ndarray) -> np.ndarray | None:
    """Rows of message payloads at ``offsets`` in a chunk, if they all have one size. Messages
    at a regular stride (a fixed set of topics per tick) are cut with one strided view."""
    if offsets.size == 0:
        return np.zeros((0, 0), np.uint8)
    o = offsets.astype(np.int64)
    steps = np.diff(o)
    stride = int(steps[0]) if steps.size else 1
    regular = stride > 0 and bool(np.all(steps == stride))
    if o[0] < 0 or o[-1] + _MESSAGE_HEAD > chunk.size:
        return None
    if regular:
        lengths = as_strided(chunk[o[0] + 1:], shape=(o.size, 8), strides=(stride, 1))
    else:
        lengths = chunk[o[:, None] + np.arange(1, 9)]
    lengths = lengths.copy().view("<u8")[:, 0]
    if np.any(lengths != lengths[0]) or o[-1] + 9 + int(lengths[0]) > chunk.size:
        return None
    size = int(lengths[0]) - _MESSAGE.size
    if regular:
        return as_strided(chunk[o[0] + _MESSAGE_HEAD:], shape=(o.size, size),
                          strides=(stride, 1)).copy()
    return chunk[o[:, None] + _MESSAGE_HEAD + np.arange(size)]
