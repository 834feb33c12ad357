"""Reading an MCAP file's messages fast: the file is memory-mapped and walked record by record
with ``struct``, and chunks are decompressed whole (``mcap_index`` cuts one channel of
fixed-size messages out of every chunk at once with numpy instead).

Why not the ``mcap`` library's readers: measured on this project's machines they take 3.5 µs
(stream reader) and 4.8 µs (seeking reader) a message, building a record object for each; this
walk takes about 0.38 µs, ten times less, and the numpy path a few ns, which is what replay at
speed and an hour of 1 kHz data need. The library still supplies the opcodes, the magic and
the reading of every record that is not a message (schemas, channels, metadata, chunk
headers).

Damage does not end the walk. Each chunk's CRC is checked, so damaged bytes are found, not
decoded; a chunk that fails is skipped, and where the record framing itself is broken the walk
scans forward for the next chunk whose header adds up and whose CRC verifies, and goes on from
there, so every intact chunk is read. Each damaged part is reported in ``problems`` with what it
held (``mcap_damage``), as is a file that ends without its summary (a crash). Pages of the map
behind the walk are handed back to the kernel, so a walk over a long file keeps its memory
bounded.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterator
from pathlib import Path

import zstandard
from mcap.opcode import Opcode
from mcap.records import Chunk, Metadata
from mcap.writer import MCAP0_MAGIC as MAGIC

from .mcap_damage import chunk_loss, describe, region_loss
from .mcap_mapped import MappedFile, what_it_is
from .mcap_records import (
    KNOWN_OPS,
    MESSAGE_FIELDS,
    OP_CHANNEL,
    OP_CHUNK,
    OP_DATA_END,
    OP_FOOTER,
    OP_MESSAGE,
    OP_MESSAGE_INDEX,
    OP_METADATA,
    OP_SCHEMA,
    RECORD_HEAD,
    Channels,
    RecordBody,
    chunk_framing,
)
from .mcap_summary import message_index_at

__all__ = ["MESSAGE_FIELDS", "OP_CHANNEL", "OP_CHUNK", "OP_MESSAGE", "OP_MESSAGE_INDEX",
           "OP_SCHEMA", "RECORD_HEAD", "DamagedChunk", "MappedFile", "McapScan", "what_it_is"]
_RELEASE_BEHIND = 16 << 20          # mapped bytes a walk keeps behind it before handing back


class DamagedChunk(ValueError):
    """A chunk that does not decompress or fails its CRC check."""


class McapScan:
    """One walk over an MCAP file: a path (mapped here, closed on exit; use as a context
    manager) or a ``MappedFile`` shared with other walks (left open). Schemas, channels and
    metadata records met on the walk are collected (channels from a sound summary too, so a
    damaged first chunk does not orphan the messages after it); damage goes into
    ``problems``."""

    def __init__(self, source: str | Path | MappedFile, problems: list[str]) -> None:
        self._owned = not isinstance(source, MappedFile)
        self.file = MappedFile(source) if self._owned else source
        self.path, self.data, self.view = self.file.path, self.file.data, self.file.view
        self.problems = problems
        self.summary = self.file.summary
        self.channels = Channels()
        if self.summary is not None:
            for schema in self.summary.schemas.values():
                self.channels.add_schema(schema)
            for channel in self.summary.channels.values():
                self.channels.add_channel(channel)
        stats = None if self.summary is None else self.summary.statistics
        self.origin_ns = stats.message_start_time if stats and stats.message_count else None
        self.read_until_ns: int | None = None     # the last log time met before the walk's spot
        self.metadata: dict[str, dict[str, str]] = {}     # metadata records met on the walk
        self.finished = False                     # the footer was reached
        self.chunks_met = 0
        self.gaps = 0                             # losses with the walk going on after them
        self._bad: str | None = None              # set by a consumer: the record just yielded
        self._verified: tuple[int, memoryview] | None = None
        self._decompress = zstandard.ZstdDecompressor().decompress

    def __enter__(self) -> McapScan:
        return self

    def __exit__(self, *exc) -> None:
        if self._owned:
            self.file.close()

    # ---- the walk ------------------------------------------------------------------------
    def records(self) -> Iterator[tuple[int, int, int]]:
        """Top-level records as (opcode, body start, body end). Broken framing is skipped
        to the next intact chunk; a consumer that finds the record it was given broken calls
        ``bad_record`` before asking for the next."""
        view, size = self.view, len(self.data)
        if not self.file.is_mcap:
            self.problems.append(f"{self.path.name}: not an MCAP file ({what_it_is(view)})")
            return
        pos = released = len(MAGIC)
        while pos < size:
            why = self._framing(pos, size)
            if why is None:
                op, length = RECORD_HEAD.unpack_from(view, pos)
                start, end = pos + RECORD_HEAD.size, pos + RECORD_HEAD.size + length
                if op == OP_FOOTER:
                    self.finished = True
                    return
                if op == OP_CHUNK:
                    self.chunks_met += 1
                    first, last = struct.unpack_from("<QQ", view, start)
                    self.origin_ns = first if self.origin_ns is None else self.origin_ns
                    self.read_until_ns = max(last, self.read_until_ns or last)
                yield op, start, end
                if self._bad is None:
                    pos = end
                    if pos - released > 2 * _RELEASE_BEHIND:
                        self.file.release(released, pos - _RELEASE_BEHIND)
                        released = pos - _RELEASE_BEHIND
                    continue
                why, self._bad = self._bad, None
            resumed = self.resync(pos + 1)
            self._report_region(pos, resumed, why)
            if resumed is None:
                return
            pos = resumed
        self.problems.append(
            f"{self.path.name}: no summary: the file ends at byte {size} without one (the "
            "recording did not finish: a crash, a kill or a full disk); "
            + describe(region_loss(view, None, size, None), self.channels, self.origin_ns,
                       self.read_until_ns))

    def bad_record(self, why: str) -> None:
        """The record just yielded by ``records`` contradicts itself: skip to the next intact
        chunk instead of past it."""
        self._bad = why

    def _framing(self, pos: int, size: int) -> str | None:
        """None if the record at ``pos`` is framed soundly, else what is wrong."""
        if pos + RECORD_HEAD.size > size:
            return "cut short inside a record header"
        op, length = RECORD_HEAD.unpack_from(self.view, pos)
        if op not in KNOWN_OPS and op < 0x80:
            return f"an unknown record type 0x{op:02x}"
        if pos + RECORD_HEAD.size + length > size:
            name = Opcode(op).name.lower().replace("_", " ") if op in KNOWN_OPS else "private"
            return f"cut short: a {name} record of {length} bytes runs past the end"
        if op == OP_CHUNK:
            return chunk_framing(self.view, pos + RECORD_HEAD.size,
                                 pos + RECORD_HEAD.size + length)
        if op == OP_MESSAGE_INDEX and message_index_at(self.view, pos) is None:
            return "a damaged message index"
        return None

    def resync(self, pos: int) -> int | None:
        """Where the walk goes on after damage at ``pos - 1``: the next chunk record whose
        header adds up and whose CRC verifies, else the end of the data section if the file
        has a sound summary, else None."""
        view, summary = self.view, self.summary
        limit = summary.summary_start if summary is not None else len(self.data)
        at = self.data.find(bytes([OP_CHUNK]), pos, limit) if pos < limit else -1
        while at != -1:
            if at + RECORD_HEAD.size <= limit:
                _, length = RECORD_HEAD.unpack_from(view, at)
                start, end = at + RECORD_HEAD.size, at + RECORD_HEAD.size + length
                if end <= limit and chunk_framing(view, start, end) is None:
                    try:
                        self._verified = (start, self.decode_chunk(start, end))
                        return at
                    except (DamagedChunk, struct.error, ValueError):
                        pass
            at = self.data.find(bytes([OP_CHUNK]), at + 1, limit)
        if summary is None or summary.summary_start < pos:
            return None
        data_end = summary.summary_start - RECORD_HEAD.size - 4
        return data_end if data_end >= pos and view[data_end] == OP_DATA_END \
            else summary.summary_start

    def _report_region(self, pos: int, resumed: int | None, why: str) -> None:
        size = len(self.data)
        lost = region_loss(self.view, self.summary, pos, resumed)
        before = None
        if resumed is not None and self.view[resumed] == OP_CHUNK:
            (before,) = struct.unpack_from("<Q", self.view, resumed + RECORD_HEAD.size)
            after = "reading went on at the next intact chunk"
        elif resumed is not None:
            after = "the summary after it is intact"
        else:
            after = "nothing after it could be read; everything before was read"
        where = f"bytes {pos}–{resumed} unreadable" if resumed is not None else \
            f"unreadable from byte {pos} of {size}"
        self.gaps += resumed is not None
        self.problems.append(f"{self.path.name}: {where} ({why}): " + describe(
            lost, self.channels, self.origin_ns, self.read_until_ns, before) + f"; {after}")

    # ---- chunks --------------------------------------------------------------------------
    def decode_chunk(self, start: int, end: int, decompressor=None) -> memoryview:
        """The decompressed, CRC-checked records of the chunk whose body is [start, end)
        (pass a decompressor of its own from another thread); DamagedChunk if they fail."""
        if self._verified is not None and self._verified[0] == start:
            return self._verified[1]
        try:
            chunk = Chunk.read(RecordBody(self.view[start:end]))
        except (struct.error, ValueError):
            raise DamagedChunk("a chunk longer than its record") from None
        compression, payload = chunk.compression, chunk.data
        size, crc = chunk.uncompressed_size, chunk.uncompressed_crc
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
                raise DamagedChunk(f"unknown chunk compression '{compression}'")
        except DamagedChunk:
            raise
        except Exception as exc:                        # zstd/lz4 errors on damaged data
            raise DamagedChunk(f"does not decompress: {exc}") from None
        if len(records) != size:
            raise DamagedChunk(f"decompresses to {len(records)} bytes, not {size}")
        if crc and zlib.crc32(records) != crc:
            raise DamagedChunk("fails its CRC check")
        return records

    def report_chunk(self, start: int, end: int, why: str, number: int | None = None) -> None:
        """Report the chunk whose body is [start, end) as lost, with what it held."""
        at = start - RECORD_HEAD.size
        stats = None if self.summary is None else self.summary.statistics
        name = f"chunk {number}" + (f" of {stats.chunk_count}" if stats else "") \
            if number is not None else "a chunk"
        lost = chunk_loss(self.view, self.summary, at, end)
        self.problems.append(
            f"{self.path.name}: {name} (bytes {at}–{end}) {why}: "
            + describe(lost, self.channels, self.origin_ns, None)
            + "; the walk went on past it")
        self.gaps += 1

    def chunk_records(self, start: int, end: int) -> memoryview | None:
        """``decode_chunk``, or None with the loss reported."""
        try:
            return self.decode_chunk(start, end)
        except DamagedChunk as exc:
            self.report_chunk(start, end, str(exc), self.chunks_met)
            return None

    def messages(self, channel_ids: set[int] | None = None
                 ) -> Iterator[tuple[int, int, int, memoryview]]:
        """(channel id, log time, publish time, data) of every readable message in file order;
        schemas and channels are collected into ``self.channels`` on the way."""
        ch, view = self.channels, self.view
        for op, start, end in self.records():
            try:
                if op == OP_CHUNK:
                    records = self.chunk_records(start, end)
                    if records is not None:
                        yield from self.chunk_messages(records, channel_ids)
                elif op == OP_MESSAGE:
                    cid, _, log, pub = MESSAGE_FIELDS.unpack_from(view, start)
                    self.origin_ns = log if self.origin_ns is None else self.origin_ns
                    self.read_until_ns = max(log, self.read_until_ns or log)
                    if channel_ids is None or cid in channel_ids:
                        yield cid, log, pub, view[start + MESSAGE_FIELDS.size:end]
                elif op == OP_SCHEMA:
                    ch.read_schema(view[start:end])
                elif op == OP_CHANNEL:
                    ch.read_channel(view[start:end])
                elif op == OP_METADATA:
                    record = Metadata.read(RecordBody(view[start:end]))
                    self.metadata[record.name] = record.metadata
            except (struct.error, ValueError) as exc:    # a record that contradicts itself
                self.bad_record(f"a bad record: {exc}")

    def chunk_messages(self, records: memoryview, channel_ids: set[int] | None
                       ) -> Iterator[tuple[int, int, int, memoryview]]:
        """Like ``messages`` within one chunk's decompressed records (ValueError on damage)."""
        pos, size = 0, len(records)
        unpack_record, unpack_message = RECORD_HEAD.unpack_from, MESSAGE_FIELDS.unpack_from
        while pos + 9 <= size:
            op, length = unpack_record(records, pos)
            start = pos + 9
            pos = start + length
            if pos > size:
                raise ValueError(f"record of {length} bytes at {start - 9} of {size}")
            if op == OP_MESSAGE:
                cid, _, log, pub = unpack_message(records, start)
                if channel_ids is None or cid in channel_ids:
                    yield cid, log, pub, records[start + MESSAGE_FIELDS.size:pos]
            elif op == OP_SCHEMA:
                self.channels.read_schema(records[start:pos])
            elif op == OP_CHANNEL:
                self.channels.read_channel(records[start:pos])
