"""One channel of fixed-size messages cut out of every chunk of an MCAP file at once, with
numpy through the message indexes that follow each chunk: a few ns a message, where even the
fast walk (``mcap_scan``) takes 0.38 µs, so an hour of 1 kHz joint_states reads in a second.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import zstandard
from numpy.lib.stride_tricks import as_strided

from .mcap_scan import (
    MESSAGE_FIELDS,
    OP_CHANNEL,
    OP_CHUNK,
    OP_MESSAGE,
    OP_MESSAGE_INDEX,
    OP_SCHEMA,
    RECORD_HEAD,
    McapScan,
)

# a message index's head (channel, length of its entries) before its (log time, offset)
# pairs: read here at once with numpy, where the library would build a tuple per entry
_INDEX_HEAD = struct.Struct("<HI")
_MESSAGE_HEAD = RECORD_HEAD.size + MESSAGE_FIELDS.size     # bytes before a message's data


def fixed_size_channel(scan: McapScan, topic: str,
                       convert: Callable[[np.ndarray], np.ndarray], workers: int = 2
                       ) -> np.ndarray | None:
    """Every message of ``topic``, cut out of each chunk at once through the message index
    that follows it as rows of bytes, passed through ``convert`` (rows -> 2-D array) and
    stacked. Chunks are decompressed, cut and converted on ``workers`` threads (zstd and
    numpy let go of the GIL). None if the topic's messages differ in size or a chunk has
    no index: the caller then walks the messages."""
    try:
        jobs = _index_jobs(scan, topic)
    except (struct.error, ValueError):
        return None                                  # damaged: the walk reports where
    if jobs is None:
        return None

    def job(chunk_start: int, chunk_end: int, pairs: np.ndarray) -> np.ndarray | None:
        try:
            records = scan.chunk_records(chunk_start, chunk_end,
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


def _index_jobs(scan: McapScan, topic: str) -> list[tuple[int, int, np.ndarray]] | None:
    """(chunk body start, end, message index pairs of ``topic``) for every chunk, or None
    if a chunk has no index or messages lie outside chunks."""
    jobs: list[tuple[int, int, np.ndarray]] = []
    chunk: tuple[int, int] | None = None
    target: int | None = None
    unindexed = False                    # a chunk with no message index after it
    for op, start, end in scan.records():
        v = scan.view
        if op == OP_CHUNK:
            if unindexed:
                return None
            chunk, unindexed = (start, end), True
            if target is None:                      # channel records live in the chunks
                records = scan.chunk_records(start, end)
                if records is None:
                    break
                for _ in scan.chunk_messages(records, set()):
                    pass
                target = next((c for c, t in scan.channels.topics.items() if t == topic),
                              None)
        elif op == OP_MESSAGE_INDEX and chunk is not None:
            unindexed = False
            cid, n = _INDEX_HEAD.unpack_from(v, start)
            if cid == target:                       # (log time, offset) pairs
                at = start + _INDEX_HEAD.size
                jobs.append((*chunk, np.frombuffer(v[at:at + n], dtype="<u8").reshape(-1, 2)))
        elif op == OP_MESSAGE:
            return None                              # messages outside chunks: walk them
        elif op == OP_CHANNEL:
            scan.channels.read_channel(v[start:end])
        elif op == OP_SCHEMA:
            scan.channels.read_schema(v[start:end])
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
    size = int(lengths[0]) - MESSAGE_FIELDS.size
    if regular:
        return as_strided(chunk[o[0] + _MESSAGE_HEAD:], shape=(o.size, size),
                          strides=(stride, 1)).copy()
    return chunk[o[:, None] + _MESSAGE_HEAD + np.arange(size)]
