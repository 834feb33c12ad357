"""An MCAP file opened and memory-mapped once, shared by every walk over it (``mcap_scan``)
and by the ``mcap`` library's seeking reader; its summary read once (``mcap_summary``)."""

from __future__ import annotations

import mmap
import os
from functools import cached_property
from pathlib import Path

from mcap.writer import MCAP0_MAGIC as MAGIC

from .mcap_summary import FileSummary, read_summary


class MappedFile:
    """One MCAP file opened and memory-mapped once, for any number of walks (``McapScan``)
    and for the library's seeking reader (``file``)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.file = open(self.path, "rb")
        try:
            size = os.fstat(self.file.fileno()).st_size
            self.data = mmap.mmap(self.file.fileno(), 0, access=mmap.ACCESS_READ) if size \
                else b""
        except BaseException:
            self.file.close()
            raise
        self.view = memoryview(self.data)

    @cached_property
    def summary(self) -> FileSummary | None:
        """The file's sound summary section, or None (``mcap_summary``)."""
        return read_summary(self.view)

    @property
    def is_mcap(self) -> bool:
        return bytes(self.view[:len(MAGIC)]) == MAGIC

    def release(self, start: int, end: int) -> None:
        """Let the kernel drop the mapped pages within [start, end) from this process (they
        stay in the page cache and come back if read again)."""
        start += -start % mmap.PAGESIZE
        end -= end % mmap.PAGESIZE
        if end > start and isinstance(self.data, mmap.mmap):
            self.data.madvise(mmap.MADV_DONTNEED, start, end - start)

    def close(self) -> None:
        self.file.close()
        try:
            self.view.release()
            if isinstance(self.data, mmap.mmap):
                self.data.close()
        except BufferError:
            pass                # views handed out still live; the map goes with the last one


def what_it_is(view: memoryview) -> str:
    """A file that is not MCAP, in a few words."""
    head = bytes(view[:16])
    if not head:
        return "an empty file"
    if head.startswith(b"SQLite format 3"):
        return "an SQLite database: rosbag2's sqlite3 storage, which these tools do not read"
    return "it does not start with the MCAP magic bytes"
