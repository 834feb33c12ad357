"""What a damaged part of an MCAP file held, in words, for the problems a walk reports.

A damaged chunk's messages are counted, per topic, from its message indexes (the records right
after it, or the ones the summary's chunk index points at), which lie outside the damaged bytes;
its time span comes from the indexes or the chunk's header. Where none of these survive (a
crashed file with no summary), the report says the count is unknown and gives the time after
which messages are missing.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .mcap_records import CHUNK_FIXED, RECORD_HEAD, Channels
from .mcap_summary import FileSummary, message_index_at

if TYPE_CHECKING:
    from mcap.records import ChunkIndex


@dataclass
class Lost:
    """Messages lost in a damaged part: per channel id (None: how many is unknown) and the
    span of their log times [ns] where known."""

    counts: dict[int, int] | None = None
    first_ns: int | None = None
    last_ns: int | None = None
    chunks: int = 0
    uncounted: int = 0                    # chunks whose message indexes are damaged too

    @property
    def messages(self) -> int | None:
        return None if self.counts is None else sum(self.counts.values())

    def add_index(self, channel: int, pairs: memoryview) -> None:
        times = np.frombuffer(pairs, "<u8")[0::2]
        self.counts = {} if self.counts is None else self.counts
        self.counts[channel] = self.counts.get(channel, 0) + times.size
        if times.size:
            self.span(int(times.min()), int(times.max()))

    def span(self, first: int, last: int) -> None:
        self.first_ns = first if self.first_ns is None else min(self.first_ns, first)
        self.last_ns = last if self.last_ns is None else max(self.last_ns, last)


def chunk_loss(view: memoryview, summary: FileSummary | None, record_at: int,
               end: int) -> Lost:
    """What the chunk record at ``record_at`` (its body ending at ``end``) held."""
    lost = Lost(chunks=1)
    entry = None if summary is None else next(
        (c for c in summary.chunk_indexes() if c.chunk_start_offset == record_at), None)
    if entry is not None:
        _from_entries(view, [entry], lost)
    else:
        pos = end                                 # the chunk's own indexes follow it
        while (found := message_index_at(view, pos)) is not None:
            channel, pairs, pos = found
            lost.add_index(channel, pairs)
    if lost.first_ns is None and end - record_at >= RECORD_HEAD.size + CHUNK_FIXED.size:
        first, last, *_ = CHUNK_FIXED.unpack_from(view, record_at + RECORD_HEAD.size)
        lost.span(first, last)
    return lost


def region_loss(view: memoryview, summary: FileSummary | None, start: int,
                end: int | None) -> Lost:
    """What bytes [start, end) held (end None: to the end of the file), from the summary's
    chunk indexes; the count is unknown without a summary."""
    lost = Lost()
    if summary is not None:
        entries = summary.chunks_in(start, end if end is not None else summary.summary_start)
        lost.counts = {}
        lost.chunks = len(entries)
        _from_entries(view, entries, lost)
    return lost


def _from_entries(view: memoryview, entries: list[ChunkIndex], lost: Lost) -> None:
    lost.counts = {} if lost.counts is None else lost.counts
    for entry in entries:
        lost.span(entry.message_start_time, entry.message_end_time)
        indexes = [message_index_at(view, offset)
                   for offset in entry.message_index_offsets.values()]
        for found in indexes:
            if found is not None:
                lost.add_index(*found[:2])
        lost.uncounted += any(found is None for found in indexes)


def describe(lost: Lost, channels: Channels, origin_ns: int | None, after_ns: int | None,
             before_ns: int | None = None) -> str:
    """``lost`` in words: how many messages, of which topics, logged when (seconds after the
    file's first message ``origin_ns``); where the lost messages' own times are unknown,
    ``after_ns`` and ``before_ns`` bound them (the last log time read before the damage, the
    first after it)."""
    n = lost.messages
    if n is None:
        what = "an unknown number of messages lost (the file has no summary to count them)"
    else:
        topics = ", ".join(f"{channels.topic(c)} {k}" for c, k in sorted(lost.counts.items())
                           if k)
        what = ("at least " if lost.uncounted else "") + f"{n} messages lost" \
            + (f" in {lost.chunks} chunks" if lost.chunks > 1 else "") \
            + (f" ({topics})" if topics else "")
        if lost.uncounted:
            what += (f"; the message indexes of {lost.uncounted} of these chunks are damaged "
                     "too, so their messages are not counted")
    if origin_ns is None:
        return what
    if lost.first_ns is not None and lost.last_ns is not None:
        return (f"{what}, logged {_s(lost.first_ns, origin_ns)}–"
                f"{_s(lost.last_ns, origin_ns)} s after the file's first message")
    if after_ns is not None and before_ns is not None:
        return (f"{what}, logged between {_s(after_ns, origin_ns)} and "
                f"{_s(before_ns, origin_ns)} s after the file's first message")
    if after_ns is not None:
        return f"{what}, logged after {_s(after_ns, origin_ns)} s into the file"
    return what


def _s(t: int, origin: int) -> str:
    return f"{(t - origin) * 1e-9:.3f}"
