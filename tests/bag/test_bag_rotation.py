"""A bag split: the finished file is completed on the writer's closing thread, so the caller
that writes (the node's tick) goes on at once; the bag is whole once closed."""

from __future__ import annotations

import threading

from rosbags.rosbag2 import Reader

from drill_sim.bag import reader
from drill_sim.bag.mcap_file import McapFileWriter
from drill_sim.bag.writer import BagWriter

T0 = 1_700_000_000_000_000_000


def test_a_split_finishes_the_old_file_off_the_writing_thread(tmp_path, monkeypatch):
    release, started = threading.Event(), threading.Event()
    finishing: list[threading.Thread] = []
    real_finish = McapFileWriter.finish

    def held_finish(self) -> None:          # a file whose completion takes a while
        finishing.append(threading.current_thread())
        started.set()
        release.wait(10.0)
        real_finish(self)

    monkeypatch.setattr(McapFileWriter, "finish", held_finish)
    bag = tmp_path / "rotated"
    w = BagWriter(bag, split_duration_s=1.0)
    w.add_topic("/a", "std_msgs/msg/Float64")
    data = b"\x00\x01\x00\x00" + bytes(8)
    for i in range(30):                     # 3 s of messages at 10 Hz: two splits
        w.write("/a", data, T0 + i * 100_000_000)
    assert len(w.files) == 2 and started.wait(10.0)
    assert threading.current_thread() not in finishing    # not on the writing thread
    release.set()
    w.close()
    assert [f.name for f in sorted(bag.glob("*.mcap"))] == [
        "rotated_0.mcap", "rotated_1.mcap", "rotated_2.mcap"]
    found = reader.info(bag)
    assert found.message_count == 30 and not found.problems
    with Reader(bag) as r:
        assert r.message_count == 30
