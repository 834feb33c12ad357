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
from dataclasses import dataclass, field

from mcap.opcode import Opcode
from mcap.records import Channel, ChunkIndex, Schema, Statistics
from mcap.writer import MCAP0_MAGIC as MAGIC

from .mcap_records import RECORD_HEAD, RecordBody

_FOOTER = struct.Struct("<QQI")                   # summary start, offsets start, CRC
_FOOTER_RECORD = RECORD_HEAD.size + _FOOTER.size
_INDEX_HEAD = struct.Struct("<HI")                # a message index: channel, entries length


@dataclass
class FileSummary:
    """A sound summary section (its CRC checked) and the footer that points at it."""

    summary_start: int
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    statistics: Statistics | None = None
    chunk_indexes: list[ChunkIndex] = field(default_factory=list)

    def chunks_in(self, start: int, end: int | None) -> list[ChunkIndex]:
        """The chunks whose records start in bytes [start, end) (end None: to the end)."""
        return [c for c in self.chunk_indexes if start <= c.chunk_start_offset
                and (end is None or c.chunk_start_offset < end)]


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
    if not len(MAGIC) <= start <= footer_at:
        return None
    if crc and zlib.crc32(view[start:footer_at + RECORD_HEAD.size + 16]) != crc:
        return None
    found = FileSummary(start)
    pos = start
    try:
        while pos < footer_at:
            op, length = RECORD_HEAD.unpack_from(view, pos)
            body = view[pos + RECORD_HEAD.size:pos + RECORD_HEAD.size + length]
            pos += RECORD_HEAD.size + length
            if pos > footer_at:
                return None
            if op == Opcode.SCHEMA:
                schema = Schema.read(RecordBody(body))
                schema.data = bytes(schema.data)
                found.schemas[schema.id] = schema
            elif op == Opcode.CHANNEL:
                channel = Channel.read(RecordBody(body))
                found.channels[channel.id] = channel
            elif op == Opcode.STATISTICS:
                found.statistics = Statistics.read(RecordBody(body))
            elif op == Opcode.CHUNK_INDEX:
                found.chunk_indexes.append(ChunkIndex.read(RecordBody(body)))
    except (struct.error, ValueError):
        return None
    return found


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
