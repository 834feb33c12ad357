"""Repair never loses data: it keeps every intact chunk after a bad one, keeps each original byte
for byte under a fresh name, changes nothing when it cannot finish (too little space, a failed
write) or has nothing to do (a sound bag), refuses what is not an MCAP bag, and says what the
damage cost, in its output and in the repaired file."""

from __future__ import annotations

import errno
import shutil
from pathlib import Path

import pytest
from bagutil import chunk_spans, rig_bag
from rosbags.rosbag2 import Reader

from drill_sim.bag import reader
from drill_sim.bag.errors import BagError
from drill_sim.bag.mcap_file import McapFileWriter
from drill_sim.cli.main import main
from drill_sim.wire.rig_topics import OUTPUTS

TICKS = 2000
TOTAL = TICKS * len(OUTPUTS)


def _bag(tmp_path) -> tuple[Path, Path]:
    bag = tmp_path / "rig"
    rig_bag(bag, TICKS, chunk_size=60_000)
    return bag, bag / "rig_0.mcap"




def _flip_chunk(path, k: int) -> int:
    """Flip one byte in the middle of chunk ``k``; the messages it held."""
    start, end, lost = chunk_spans(path)[k]
    data = bytearray(path.read_bytes())
    data[(start + end) // 2] ^= 0x20
    path.write_bytes(bytes(data))
    return lost


def _cut_inside_chunk(path, k: int) -> int:
    """Cut the file in the middle of chunk ``k`` (a crash); the messages before it."""
    chunks = chunk_spans(path)
    start, end, _ = chunks[k]
    path.write_bytes(path.read_bytes()[:(start + end) // 2])
    return sum(c[2] for c in chunks[:k])


def _snapshot(bag: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(bag.iterdir())}


def test_repair_keeps_every_intact_chunk_after_a_bad_one(tmp_path):
    bag, path = _bag(tmp_path)
    lost = _flip_chunk(path, 1)
    damaged = path.read_bytes()
    repaired = reader.repair(bag)
    assert repaired.message_count == TOTAL - lost
    with Reader(bag) as r:
        assert r.message_count == TOTAL - lost
    assert (bag / "rig_0.mcap.damaged").read_bytes() == damaged


def test_repairing_twice_never_overwrites_the_crashed_original(tmp_path, capsys):
    bag, path = _bag(tmp_path)
    kept = _cut_inside_chunk(path, 3)
    (bag / "metadata.yaml").unlink()
    crashed = path.read_bytes()
    assert main(["bag", "repair", str(bag)]) == 0
    assert reader.info(bag).message_count == kept
    after_first = _snapshot(bag)
    assert after_first["rig_0.mcap.damaged"] == crashed
    capsys.readouterr()
    assert main(["bag", "repair", str(bag)]) == 2
    assert "nothing to repair" in capsys.readouterr().err
    assert _snapshot(bag) == after_first


def test_an_earlier_original_is_kept_beside_the_new_one(tmp_path):
    bag, path = _bag(tmp_path)
    earlier = b"an original an earlier repair kept"
    (bag / "rig_0.mcap.damaged").write_bytes(earlier)
    _flip_chunk(path, 2)
    damaged = path.read_bytes()
    reader.repair(bag)
    assert (bag / "rig_0.mcap.damaged").read_bytes() == earlier
    assert (bag / "rig_0.mcap.damaged.1").read_bytes() == damaged


def test_too_little_free_space_changes_nothing(tmp_path, monkeypatch, capsys):
    bag, path = _bag(tmp_path)
    _flip_chunk(path, 1)
    before = _snapshot(bag)
    real = shutil.disk_usage

    def full(p):
        return real(p)._replace(free=4096)

    monkeypatch.setattr(shutil, "disk_usage", full)
    with pytest.raises(BagError, match="not enough free space"):
        reader.repair(bag)
    assert main(["bag", "repair", str(bag)]) == 2
    assert "nothing was changed" in capsys.readouterr().err
    assert _snapshot(bag) == before


def test_a_write_that_fails_changes_nothing_and_a_second_repair_keeps_the_original(
        tmp_path, monkeypatch, capsys):
    """The disk fills up while writing: the first repair fails with nothing changed, and the
    one after it (space freed) keeps the original, not whatever the failed one left."""
    bag, path = _bag(tmp_path)
    _cut_inside_chunk(path, 4)
    (bag / "metadata.yaml").unlink()
    original = path.read_bytes()
    before = _snapshot(bag)
    real_write = McapFileWriter._write_now

    def filling(self, data):
        if self._written > 20_000:
            raise OSError(errno.ENOSPC, "No space left on device")
        real_write(self, data)

    monkeypatch.setattr(McapFileWriter, "_write_now", filling)
    assert main(["bag", "repair", str(bag)]) == 2
    assert "No space left on device" in capsys.readouterr().err
    assert _snapshot(bag) == before
    monkeypatch.setattr(McapFileWriter, "_write_now", real_write)
    assert main(["bag", "repair", str(bag)]) == 0
    assert original in _snapshot(bag).values()


@pytest.mark.parametrize("what", ["random", "empty", "sqlite3"])
def test_what_is_not_an_mcap_bag_is_refused_and_left_alone(tmp_path, capsys, what):
    bag = tmp_path / "bag"
    bag.mkdir()
    if what == "sqlite3":
        (bag / "bag_0.db3").write_bytes(b"SQLite format 3\x00" + bytes(4000))
        (bag / "metadata.yaml").write_text(
            "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
            "  relative_file_paths: [bag_0.db3]\n")
    else:
        (bag / "bag_0.mcap").write_bytes(bytes(range(256)) * 40 if what == "random" else b"")
    before = _snapshot(bag)
    assert main(["bag", "repair", str(bag)]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "nothing was changed" in err
    assert _snapshot(bag) == before


def test_a_sound_bag_is_refused(tmp_path, capsys):
    bag, _ = _bag(tmp_path)
    before = _snapshot(bag)
    assert main(["bag", "repair", str(bag)]) == 2
    assert "nothing to repair" in capsys.readouterr().err
    assert _snapshot(bag) == before


def test_repair_says_what_was_lost_and_the_repaired_bag_remembers(tmp_path, capsys):
    bag, path = _bag(tmp_path)
    lost = _flip_chunk(path, 1)
    assert main(["bag", "repair", str(bag)]) == 0
    out = capsys.readouterr().out
    assert f"{lost} messages lost" in out and "/drill_sim/joint_states" in out
    assert "kept as rig_0.mcap.damaged" in out
    found = reader.info(bag)                 # a gap in the data: the bag stays incomplete
    assert any("was repaired" in p and f"{lost} messages lost" in p for p in found.problems)


def test_a_repaired_crash_is_sound_with_a_note(tmp_path):
    """A crash loses the end of a recording: once repaired, the bag is whole up to the cut."""
    bag, path = _bag(tmp_path)
    kept = _cut_inside_chunk(path, 3)
    repaired = reader.repair(bag)
    assert repaired.message_count == kept and not repaired.problems
    assert any("was repaired" in n for n in repaired.notes)


def test_repair_of_a_split_bag_rewrites_only_the_damaged_file(tmp_path):
    from test_bag import _write

    bag = tmp_path / "split"
    _write(bag, n=3000, split_duration_s=10.0, chunk_size=8192)
    files = sorted(bag.glob("*.mcap"))
    assert len(files) == 3
    before = {f.name: f.read_bytes() for f in files}
    lost = _flip_chunk(files[1], 2)
    repaired = reader.repair(bag)
    assert repaired.message_count == 6300 - lost
    after = _snapshot(bag)
    assert after["split_0.mcap"] == before["split_0.mcap"]
    assert after["split_2.mcap"] == before["split_2.mcap"]
    assert "split_0.mcap.damaged" not in after and "split_1.mcap.damaged" in after
    with Reader(bag) as r:
        assert r.message_count == 6300 - lost
