"""What every reader of MCAP records here shares: the opcodes as plain ints, the two layouts
met once per message as precompiled ``struct``\\ s, a record body the ``mcap`` library's record
classes read from (``Schema.read`` ...), and the schemas and channels a walk has met."""

from __future__ import annotations

import io
import struct
from dataclasses import dataclass, field

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import Channel, Schema

# the library's opcodes as plain ints, compared once per record on the walk
OP_SCHEMA, OP_CHANNEL, OP_MESSAGE = int(Opcode.SCHEMA), int(Opcode.CHANNEL), int(Opcode.MESSAGE)
OP_CHUNK, OP_MESSAGE_INDEX = int(Opcode.CHUNK), int(Opcode.MESSAGE_INDEX)
OP_FOOTER, OP_METADATA, OP_DATA_END = int(Opcode.FOOTER), int(Opcode.METADATA), \
    int(Opcode.DATA_END)
KNOWN_OPS = frozenset(int(o) for o in Opcode)
RECORD_HEAD = struct.Struct("<BQ")                 # opcode, body length
MESSAGE_FIELDS = struct.Struct("<HIQQ")             # channel, sequence, log time, publish time
CHUNK_FIXED = struct.Struct("<QQQII")              # start, end, size, CRC, compression length


class RecordBody(ReadDataStream):
    """One record body in memory, for the library's record readers (``Schema.read`` ...).
    Bytes come as views, not copies; a field running past the body raises ValueError (over
    a file the library would read short); strings decode leniently, so a bad name is shown,
    not fatal."""

    def __init__(self, body: memoryview) -> None:
        super().__init__(io.BytesIO())                 # unused: reads come from ``body``
        self._body = body

    def read(self, length: int) -> memoryview:
        start = self._count
        if length < 0 or start + length > len(self._body):
            raise ValueError("field longer than its record")
        self._count = start + length
        return self._body[start:start + length]

    def read_prefixed_string(self) -> str:
        length = self.read4()
        if self._count + length > len(self._body):
            raise ValueError("string longer than its record")
        return bytes(self.read(length)).decode("utf-8", "replace")


@dataclass
class Channels:
    """Schemas and channels seen so far (the library's records): id -> topic and id -> type
    name, and the records."""

    schemas: dict[int, Schema] = field(default_factory=dict)
    records: dict[int, Channel] = field(default_factory=dict)
    topics: dict[int, str] = field(default_factory=dict)
    types: dict[int, str] = field(default_factory=dict)

    def read_schema(self, body: memoryview) -> None:
        schema = Schema.read(RecordBody(body))
        schema.data = bytes(schema.data)               # not a view into the file
        self.add_schema(schema)

    def read_channel(self, body: memoryview) -> None:
        self.add_channel(Channel.read(RecordBody(body)))

    def add_schema(self, schema: Schema) -> None:
        self.schemas[schema.id] = schema

    def add_channel(self, channel: Channel) -> None:
        self.records[channel.id] = channel
        self.topics[channel.id] = channel.topic
        schema = self.schemas.get(channel.schema_id)
        self.types[channel.id] = schema.name if schema else ""

    def topic(self, channel_id: int) -> str:
        """The channel's topic, or ``channel N`` for one never declared."""
        return self.topics.get(channel_id, f"channel {channel_id}")


def chunk_framing(view: memoryview, start: int, end: int) -> str | None:
    """None if the chunk body [start, end) is framed consistently (its compression name and
    data length add up to the record's length), else what is wrong."""
    length = end - start
    if length < CHUNK_FIXED.size + 8:
        return "a chunk too short for its header"
    *_, name_length = CHUNK_FIXED.unpack_from(view, start)
    if not 0 <= name_length <= 16 or CHUNK_FIXED.size + name_length + 8 > length:
        return "a damaged chunk header"
    at = start + CHUNK_FIXED.size
    name = bytes(view[at:at + name_length])
    (data_length,) = struct.unpack_from("<Q", view, at + name_length)
    if name not in (b"", b"zstd", b"lz4") or \
            CHUNK_FIXED.size + name_length + 8 + data_length != length:
        return "a damaged chunk header"
    return None
