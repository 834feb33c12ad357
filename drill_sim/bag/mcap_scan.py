"""Reading an MCAP file's messages fast: the file is memory-mapped and walked record by record
with ``struct``, chunks are decompressed whole, and one channel of fixed-size messages can be
cut out of every chunk at once with numpy through the message indexes.

``mcap.stream_reader`` builds an object per record (~12 us a message); this walk takes about
1 us a message, and the numpy path a few ns, which is what replay at speed and an hour of
1 kHz data need. Damage ends the walk and is reported in ``problems``; everything before it
is delivered. CRCs are not checked here (``info`` and ``repair`` read with the library).
"""

from __future__ import annotations

import mmap
import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import zstandard

OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK, OP_MESSAGE_INDEX = 0x03, 0x04, 0x05, 0x06, 0x07
OP_FOOTER, OP_DATA_END = 0x02, 0x0F
MAGIC = b"\x89MCAP0\r\n"
_RECORD = struct.Struct("<BQ")
_MESSAGE = struct.Struct("<HIQQ")
_CHUNK = struct.Struct("<QQQI")
_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")
_MESSAGE_HEAD = 1 + 8 + _MESSAGE.size              # opcode, length, fixed message fields


@dataclass
class Channels:
    """Schemas and channels seen so far: id -> topic and id -> type name."""

    schemas: dict[int, str] = field(default_factory=dict)
    topics: dict[int, str] = field(default_factory=dict)
    types: dict[int, str] = field(default_factory=dict)
    metadata: dict[int, dict[str, str]] = field(default_factory=dict)

    def read_schema(self, body: memoryview) -> None:
        (sid,) = _U16.unpack_from(body, 0)
        name, _ = _string(body, 2)
        self.schemas[sid] = name

    def read_channel(self, body: memoryview) -> None:
        cid, sid = struct.unpack_from("<HH", body, 0)
        topic, pos = _string(body, 4)
        _, pos = _string(body, pos)                    # message encoding
        (length,) = _U32.unpack_from(body, pos)
        pos += 4
        end = pos + length
        meta = {}
        while pos < end:
            key, pos = _string(body, pos)
            value, pos = _string(body, pos)
            meta[key] = value
        self.topics[cid] = topic
        self.types[cid] = self.schemas.get(sid, "")
        self.metadata[cid] = meta


def _string(buf: memoryview, pos: int) -> tuple[str, int]:
    (n,) = _U32.unpack_from(buf, pos)
    return bytes(buf[pos + 4:pos + 4 + n]).decode("utf-8", "replace"), pos + 4 + n


class McapScan:
    """One MCAP file, memory-mapped. Use as a context manager."""

    def __init__(self, path: str | Path, problems: list[str]) -> None:
        self.path = Path(path)
        self.problems = problems
        self.channels = Channels()
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

    def chunk_records(self, start: int, end: int) -> memoryview | None:
        """The decompressed records of the chunk whose body is [start, end)."""
        v = self.view
        _, _, size, _ = _CHUNK.unpack_from(v, start)
        compression, pos = _string(v, start + _CHUNK.size)
        (n,) = _U64.unpack_from(v, pos)
        pos += 8
        if pos + n > end:
            self._problem(start, "chunk longer than its record")
            return None
        payload = v[pos:pos + n]
        try:
            if compression == "zstd":
                return memoryview(self._decompress(payload, max_output_size=size))
            if compression == "":
                return payload
            if compression == "lz4":
                import lz4.frame
                return memoryview(lz4.frame.decompress(bytes(payload)))
        except Exception as exc:                        # zstd/lz4 errors on damaged data
            self._problem(start, f"chunk does not decompress: {exc}")
            return None
        self._problem(start, f"unknown chunk compression '{compression}'")
        return None

    def messages(self, channel_ids: set[int] | None = None
                 ) -> Iterator[tuple[int, int, int, memoryview]]:
        """(channel id, log time, publish time, data) of every message in file order; schemas
        and channels are collected into ``self.channels`` on the way."""
        ch = self.channels
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

    def _inner(self, records: memoryview, channel_ids: set[int] | None
               ) -> Iterator[tuple[int, int, int, memoryview]]:
        pos, size = 0, len(records)
        unpack_record, unpack_message = _RECORD.unpack_from, _MESSAGE.unpack_from
        while pos + 9 <= size:
            op, length = unpack_record(records, pos)
            start = pos + 9
            pos = start + length
            if op == OP_MESSAGE:
                cid, _, log, pub = unpack_message(records, start)
                if channel_ids is None or cid in channel_ids:
                    yield cid, log, pub, records[start + _MESSAGE.size:pos]
            elif op == OP_SCHEMA:
                self.channels.read_schema(records[start:pos])
            elif op == OP_CHANNEL:
                self.channels.read_channel(records[start:pos])

    def fixed_size_channel(self, topic: str) -> tuple[np.ndarray, np.ndarray] | None:
        """Every message of ``topic`` as (log times [ns], rows of bytes), cut out of each chunk
        at once through the message index that follows it. None if the topic's messages differ
        in size (the caller then walks the messages)."""
        times, rows = [], []
        chunk: memoryview | None = None
        target: int | None = None
        unindexed = False                    # a chunk with no message index after it
        for op, start, end in self.records():
            v = self.view
            if op == OP_CHUNK:
                if unindexed:
                    return None
                chunk = self.chunk_records(start, end)
                if chunk is None:
                    break
                unindexed = True
                if target is None:                      # channel records live in the chunks
                    for _ in self._inner(chunk, set()):
                        pass
                    target = next((c for c, t in self.channels.topics.items() if t == topic),
                                  None)
            elif op == OP_MESSAGE_INDEX and chunk is not None:
                unindexed = False
                (cid,) = _U16.unpack_from(v, start)
                if cid != target:
                    continue
                (n,) = _U32.unpack_from(v, start + 2)
                pairs = np.frombuffer(v[start + 6:start + 6 + n], dtype="<u8").reshape(-1, 2)
                got = _cut(np.frombuffer(chunk, dtype=np.uint8), pairs[:, 1])
                if got is None:
                    return None
                times.append(pairs[:, 0].copy())
                rows.append(got)
            elif op == OP_MESSAGE:
                return None                              # messages outside chunks: walk them
            elif op == OP_CHANNEL:
                self.channels.read_channel(v[start:end])
            elif op == OP_SCHEMA:
                self.channels.read_schema(v[start:end])
        if unindexed:
            return None
        if not rows:
            return np.zeros(0, np.uint64), np.zeros((0, 0), np.uint8)
        if len({r.shape[1] for r in rows}) > 1:
            return None
        return np.concatenate(times), np.concatenate(rows)


def _cut(chunk: np.ndarray, offsets: np.ndarray) -> np.ndarray | None:
    """Rows of message payloads at ``offsets`` in a chunk, if they all have one size."""
    if offsets.size == 0:
        return np.zeros((0, 0), np.uint8)
    offsets = offsets.astype(np.int64)
    lengths = chunk[offsets[:, None] + np.arange(1, 9)].copy().view("<u8")[:, 0]
    if np.any(lengths != lengths[0]) or offsets[-1] + 9 + int(lengths[0]) > chunk.size:
        return None
    size = int(lengths[0]) - _MESSAGE.size
    return chunk[offsets[:, None] + _MESSAGE_HEAD + np.arange(size)]
