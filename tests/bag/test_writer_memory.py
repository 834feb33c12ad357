"""What a bag writer keeps in memory per chunk written stays small (the summary's chunk indexes
wait on disk): the node closes a chunk at least every second and ~10 a second at max speed,
for hours."""

from __future__ import annotations

import gc
import io
import time
import tracemalloc
import weakref

import pytest
from mcap.reader import make_reader

from drill_sim.bag import reader
from drill_sim.bag.mcap_file import McapFileWriter
from drill_sim.bag.writer import BagWriter

T0 = 1_700_000_000_000_000_000
TOPICS = [f"/rig/topic_{i}" for i in range(12)]          # as many channels as the node's bag


@pytest.mark.slow("the memory kept per chunk shows only over thousands of chunks, traced "
                  "allocation by allocation")
def test_memory_kept_per_chunk_is_a_few_hundred_bytes(tmp_path):
    w = BagWriter(tmp_path / "many_chunks")            # chunks close on flush only
    for name in TOPICS:
        w.add_topic(name, "std_msgs/msg/Float64")
    data = b"\x00\x01\x00\x00" + bytes(8)
    tick = 0

    def chunks(n: int) -> None:               # every topic in every chunk, as the node writes
        nonlocal tick
        for _ in range(n):
            for _ in range(20):
                tick += 1
                for name in TOPICS:
                    w.write(name, data, T0 + tick * 1_000_000)
            w.flush()

    chunks(200)
    w._file.writer._pool.submit(lambda: None).result()    # the writing thread caught up
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    chunks(1000)
    w._file.writer._pool.submit(lambda: None).result()
    gc.collect()
    per_chunk = (tracemalloc.get_traced_memory()[0] - before) / 1000
    tracemalloc.stop()
    w.close()
    # ~200 bytes with the indexes in memory, 1.4 kB as record objects
    assert per_chunk < 40, f"{per_chunk:.0f} bytes kept per chunk"
    assert reader.info(tmp_path / "many_chunks").message_count == 1200 * 20 * len(TOPICS)


def test_a_finished_file_is_freed_at_once(tmp_path):
    """A split file's writer (its zstd context holds a few MB) goes when it is finished, not
    when the cyclic collector gets round to it: a node splitting every minute grew ~2 MB a
    file."""
    gc.disable()
    try:
        w = BagWriter(tmp_path / "split", split_duration_s=1.0)
        w.add_topic("/a", "std_msgs/msg/Float64")
        first = weakref.ref(w._file.writer)
        data = b"\x00\x01\x00\x00" + bytes(8)
        for i in range(25):                           # 2.5 s at 10 Hz: two splits
            w.write("/a", data, T0 + i * 100_000_000)
        w.close()                                     # waits for the closing thread
        assert len(w.files) == 3
        assert first() is None
    finally:
        gc.enable()


class _SlowFile(io.BytesIO):
    """A disk ten times slower than the data: every write waits."""

    def write(self, data) -> int:
        time.sleep(0.002)
        return super().write(data)


@pytest.mark.slow("a disk slowed on purpose must fall behind by many chunks for the bound "
                  "to show")
def test_chunks_waiting_for_a_slow_disk_are_bounded_and_none_is_lost():
    """The writing thread lags a slow disk; the chunks handed to it must stay under the
    writer's bound (the adding thread waits, counted) and every message must reach the file."""
    stream = _SlowFile()
    w = McapFileWriter(stream, profile="ros2", library="test", chunk_size=4096,
                       max_backlog_bytes=16 * 4096)
    channel = w.add_channel("/a", "cdr", w.add_schema("std_msgs/msg/Float64", "ros2msg", b""), {})
    peak = 0
    for i in range(20_000):
        w.add_message(channel, i, T0 + i, T0 + i, bytes(100))
        peak = max(peak, w._handed - w._done)
    w.finish()
    assert peak <= 17 * 4096 + 200, peak            # the bound plus one chunk
    assert w.backlog_waits > 0 and w.backlog_wait_s > 0
    stream.seek(0)
    messages = list(make_reader(stream).iter_messages())
    assert [m.sequence for _, _, m in messages] == list(range(20_000))
