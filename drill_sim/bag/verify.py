"""Checking every chunk of an MCAP file: each decompressed and CRC-checked on worker threads
(zstd and zlib let go of the GIL), a few at a time, so memory stays bounded. ``info`` and
``repair`` use it to tell a sound file from a damaged one whose summary still looks whole."""

from __future__ import annotations

from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor

import zstandard

from .mcap_scan import OP_CHUNK, DamagedChunk, MappedFile, McapScan


def damage(mapped: MappedFile, workers: int = 2) -> list[str]:
    """The damage found in the file, in words (``McapScan`` problems): none for a sound one.
    A file that ends without its summary is damaged (a crashed recording)."""
    problems: list[str] = []
    scan = McapScan(mapped, problems)
    pending: deque[tuple[int, int, int, Future]] = deque()

    def finish() -> None:
        start, end, number, future = pending.popleft()
        failed = future.result()
        if failed is not None:
            scan.report_chunk(start, end, str(failed), number)

    with ThreadPoolExecutor(max_workers=workers) as pool:
        for op, start, end in scan.records():
            if op == OP_CHUNK:
                pending.append((start, end, scan.chunks_met,
                                pool.submit(_check, scan, start, end)))
                while len(pending) > 2 * workers:
                    finish()
        while pending:
            finish()
    return problems


def _check(scan: McapScan, start: int, end: int) -> DamagedChunk | None:
    try:
        scan.decode_chunk(start, end, zstandard.ZstdDecompressor())
    except DamagedChunk as exc:
        return exc
    return None
