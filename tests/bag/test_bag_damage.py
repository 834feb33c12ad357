"""Damaged bags are read past the damage: a chunk that fails its CRC, broken record framing or a
damaged first chunk loses only its own messages, every intact chunk after it is read, and the
loss is reported with what it held. Readers do not trust a summary over the data, say when a
file has no summary, read a file listed twice once, and refuse what is not MCAP."""

from __future__ import annotations

import pytest
import yaml
from bagutil import chunk_spans, rig_bag

from drill_sim.bag import reader
from drill_sim.bag.errors import BagError
from drill_sim.bag.series import rig_series
from drill_sim.cli.main import main
from drill_sim.wire.rig_topics import OUTPUTS

TICKS = 3000


def _bag(tmp_path, ticks: int = TICKS):
    bag = tmp_path / "rig"
    samples = rig_bag(bag, ticks, chunk_size=60_000)
    return bag, bag / "rig_0.mcap", samples




def _messages(bag, problems=None) -> list[tuple[str, int, bytes]]:
    return [(m.topic, m.log_time_ns, m.data)
            for m in reader.read_messages(bag, problems=problems)]


def _edit(path, change) -> None:
    data = bytearray(path.read_bytes())
    change(data)
    path.write_bytes(bytes(data))


def _flip(at: int):
    def change(data: bytearray) -> None:
        data[at] ^= 0x20
    return change


def test_a_flipped_byte_loses_only_its_chunk_and_says_what(tmp_path):
    bag, path, _ = _bag(tmp_path)
    everything = _messages(bag)
    chunks = chunk_spans(path)
    assert len(chunks) >= 4 and sum(c[2] for c in chunks) == len(everything)
    start, end, lost = chunks[1]
    _edit(path, _flip((start + end) // 2))
    problems: list[str] = []
    got = _messages(bag, problems)
    before = chunks[0][2]
    assert got == everything[:before] + everything[before + lost:]
    assert len(problems) == 1
    assert f"chunk 2 of {len(chunks)}" in problems[0]
    assert f"{lost} messages lost" in problems[0] and "/drill_sim/joint_states" in problems[0]


def test_info_checks_every_chunk_instead_of_trusting_the_summary(tmp_path):
    bag, path, _ = _bag(tmp_path)
    chunks = chunk_spans(path)
    _, end, lost = chunks[2]
    _edit(path, _flip(end - 100))
    found = reader.info(bag)
    assert found.message_count == TICKS * len(OUTPUTS) - lost
    assert len(found.problems) == 1 and f"chunk 3 of {len(chunks)}" in found.problems[0]


@pytest.mark.parametrize("how", ["length", "opcode", "zeroed"])
def test_broken_framing_is_skipped_to_the_next_intact_chunk(tmp_path, how):
    bag, path, _ = _bag(tmp_path)
    everything = _messages(bag)
    chunks = chunk_spans(path)
    start, end, lost = chunks[2]

    def change(data: bytearray) -> None:
        if how == "length":
            data[start + 3] ^= 0x01                  # the record now runs far past its end
        elif how == "opcode":
            data[start] = 0x77
        else:
            data[start:end] = bytes(end - start)

    _edit(path, change)
    problems: list[str] = []
    got = _messages(bag, problems)
    before = chunks[0][2] + chunks[1][2]
    assert got == everything[:before] + everything[before + lost:]
    assert len(problems) == 1 and "unreadable" in problems[0]
    assert f"{lost} messages lost" in problems[0]


def test_a_damaged_first_chunk_leaves_the_channels_of_the_rest_known(tmp_path):
    """The node's channels are declared in the first chunk; the summary declares them too."""
    bag, path, _ = _bag(tmp_path)
    everything = _messages(bag)
    start, end, lost = chunk_spans(path)[0]
    _edit(path, _flip((start + end) // 2))
    got = _messages(bag)
    assert got == everything[lost:]
    assert reader.info(bag).topics["/drill_sim/joint_states"].count > TICKS // 2


def test_rig_series_reads_every_intact_chunk(tmp_path):
    bag, path, samples = _bag(tmp_path)
    start, end, _ = chunk_spans(path)[1]
    _edit(path, _flip((start + end) // 2))
    series = rig_series(bag)
    wob = series.wob_n.tolist()
    recorded = [s.wob_n for s in samples]
    gap = len(recorded) - len(wob)
    assert 0 < gap < TICKS // 4                       # one chunk's samples, not the rest
    cut = next(k for k, (a, b) in enumerate(zip(wob, recorded, strict=False)) if a != b)
    assert wob == recorded[:cut] + recorded[cut + gap:]


def test_a_file_ending_without_its_summary_is_reported(tmp_path):
    """A recording killed between two chunks ends cleanly at a record boundary, but without
    the summary: what came after is lost, and info says so."""
    bag, path, _ = _bag(tmp_path)
    chunks = chunk_spans(path)
    _edit(path, lambda data: data.__delitem__(slice(chunks[3][0], None)))
    (bag / "metadata.yaml").unlink()
    found = reader.info(bag)
    assert found.message_count == sum(c[2] for c in chunks[:3])
    assert any("no summary" in p for p in found.problems)


def test_a_file_listed_twice_in_metadata_yaml_is_read_once(tmp_path):
    bag, _, _ = _bag(tmp_path, ticks=500)
    meta_path = bag / "metadata.yaml"
    meta = yaml.safe_load(meta_path.read_text())
    info = meta["rosbag2_bagfile_information"]
    info["relative_file_paths"] *= 2
    info["files"] *= 2
    meta_path.write_text(yaml.safe_dump(meta))
    found = reader.info(bag)
    assert found.message_count == 500 * len(OUTPUTS)
    assert len(_messages(bag)) == 500 * len(OUTPUTS)
    assert rig_series(bag).time_s.size == 500
    assert any("lists rig_0.mcap 2 times" in n for n in found.notes)


@pytest.mark.parametrize("content, expected", [
    (b"", "an empty file"),
    (b"SQLite format 3\x00" + bytes(100), "SQLite"),
    (bytes(range(256)) * 4, "MCAP magic"),
])
def test_what_is_not_mcap_is_refused_in_one_line(tmp_path, capsys, content, expected):
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(content)
    with pytest.raises(BagError, match="not an MCAP file"):
        reader.info(junk)
    assert main(["bag", "info", str(junk)]) == 2
    err = capsys.readouterr().err
    assert "not an MCAP file" in err and expected in err and len(err.splitlines()) == 1


def test_a_loss_whose_indexes_are_damaged_too_is_counted_as_at_least(tmp_path):
    """Two chunks and the message indexes between them zeroed: the first chunk's count is
    gone with its indexes, so the report gives a lower bound, never a wrong total."""
    bag, path, _ = _bag(tmp_path)
    everything = _messages(bag)
    chunks = chunk_spans(path)
    (a, _, lost_a), (_, b, lost_b) = chunks[2], chunks[3]
    _edit(path, lambda data: data.__setitem__(slice(a, b), bytes(b - a)))
    problems: list[str] = []
    got = _messages(bag, problems)
    before = chunks[0][2] + chunks[1][2]
    assert got == everything[:before] + everything[before + lost_a + lost_b:]
    assert len(problems) == 1
    assert f"at least {lost_b} messages lost in 2 chunks" in problems[0]
    assert "indexes of 1 of these chunks are damaged too" in problems[0]
