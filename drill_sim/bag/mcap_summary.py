"""An MCAP file's footer and summary section, read straight from the mapped bytes.

The summary is what a finished file ends with: schemas, channels, statistics, one index entry
per chunk (where it lies, its time span, where its message indexes are) and the metadata
index. The walk (``mcap_scan``) takes channels from it when the chunk that declared them is
damaged, and the damage reports (``mcap_damage``) take from it what a lost chunk held. A file
whose summary is missing (a crash) or fails its CRC has none here.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field

from mcap.opcode import Opcode
from mcap.records import Channel, ChunkIndex, Metadata, MetadataIndex, Schema, Statistics
from mcap.writer import MCAP0_MAGIC as MAGIC

from .mcap_records import RECORD_HEAD, RecordBody

_FOOTER = struct.Struct("<QQI")                   # summary start, offsets start, CRC
_FOOTER_RECORD = RECORD_HEAD.size + _FOOTER.size
_INDEX_HEAD = struct.Struct("<HI")                # a message index: channel, entries length


@dataclass
class FileSummary:
    """A sound summary section (its CRC checked) and the footer that points at it. Schemas,
    channels, statistics and the metadata index are read at once; the chunk indexes (one per
    chunk, so as many as the file is long) are read when asked for, and not kept."""

    view: memoryview
    summary_start: int
    summary_end: int
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    statistics: Statistics | None = None
    metadata_indexes: list[MetadataIndex] = field(default_factory=list)

    def chunk_indexes(self) -> Iterator[ChunkIndex]:
        """The chunk index records, in file order."""
        for op, body in _records(self.view, self.summary_start, self.summary_end):
            if op == Opcode.CHUNK_INDEX:
                yield ChunkIndex.read(RecordBody(body))

    def chunks_in(self, start: int, end: int | None) -> list[ChunkIndex]:
        """The chunks whose records start in bytes [start, end) (end None: to the end)."""
        return [c for c in self.chunk_indexes() if start <= c.chunk_start_offset
                and (end is None or c.chunk_start_offset < end)]

    def metadata(self) -> dict[str, dict[str, str]]:
        """The metadata records the index points at (name -> {key: value}); one that is not
        where the index says is left out."""
        found = {}
        for entry in self.metadata_indexes:
            at, end = entry.offset, entry.offset + entry.length
            if end > len(self.view) or RECORD_HEAD.unpack_from(self.view, at)[0] \
                    != Opcode.METADATA:
                continue
            try:
                record = Metadata.read(RecordBody(self.view[at + RECORD_HEAD.size:end]))
            except (struct.error, ValueError):
                continue
            found[record.name] = dict(record.metadata)
        return found


def read_summary(view: memoryview) -> FileSummary | None:
    """The summary of the file in ``view``, or None if it has no footer, no summary, or a
    summary that fails its CRC or does not parse."""
    size = len(view)
    footer_at = size - len(MAGIC) - _FOOTER_RECORD
    if footer_at < len(MAGIC) or bytes(view[size - len(MAGIC):]) != MAGIC:
        return None
    op, length = RECORD_HEAD.unpack_from(view, footer_at)
    if op != Opcode.FOOTER or length != _FOOTER.size:
        return None
    start, _, crc = _FOOTER.unpack_from(view, footer_at + RECORD_HEAD.size)
    if not len(MAGIC) <= start < footer_at:
        return None
    if crc and zlib.crc32(view[start:footer_at + RECORD_HEAD.size + 16]) != crc:
        return None
    found = FileSummary(view, start, footer_at)
    try:
        for op, body in _records(view, start, footer_at):
            if op == Opcode.SCHEMA:
                schema = Schema.read(RecordBody(body))
                schema.data = bytes(schema.data)
                found.schemas[schema.id] = schema
            elif op == Opcode.CHANNEL:
                channel = Channel.read(RecordBody(body))
                found.channels[channel.id] = channel
            elif op == Opcode.STATISTICS:
                found.statistics = Statistics.read(RecordBody(body))
            elif op == Opcode.METADATA_INDEX:
                found.metadata_indexes.append(MetadataIndex.read(RecordBody(body)))
    except (struct.error, ValueError):
        return None
    return found


def _records(view: memoryview, start: int, end: int) -> Iterator[tuple[int, memoryview]]:
    """(opcode, body) of the records in [start, end); ValueError where one runs past it."""
    pos = start
    while pos < end:
        op, length = RECORD_HEAD.unpack_from(view, pos)
        body_end = pos + RECORD_HEAD.size + length
        if body_end > end:
            raise ValueError("a summary record runs past the summary")
        yield op, view[pos + RECORD_HEAD.size:body_end]
        pos = body_end


def message_index_at(view: memoryview, pos: int) -> tuple[int, memoryview, int] | None:
    """(channel id, its (log time, offset) pairs as little-endian uint64 bytes, the record's
    end) of the message index record at ``pos``, or None if there is no sound one there."""
    if pos + RECORD_HEAD.size + _INDEX_HEAD.size > len(view):
        return None
    op, length = RECORD_HEAD.unpack_from(view, pos)
    if op != Opcode.MESSAGE_INDEX or pos + RECORD_HEAD.size + length > len(view):
        return None
    channel, n = _INDEX_HEAD.unpack_from(view, pos + RECORD_HEAD.size)
    if _INDEX_HEAD.size + n != length or n % 16:
        return None
    at = pos + RECORD_HEAD.size + _INDEX_HEAD.size
    return channel, view[at:at + n], at + n
