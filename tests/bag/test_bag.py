"""Bags written here, read back by independent readers (rosbags, mcap-ros2-support); damaged
and foreign input."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest
from bagutil import rig_bag
from conftest import installed
from geometry_msgs.msg import TwistStamped, WrenchStamped
from mcap_ros2.reader import read_ros2_messages
from rclpy.serialization import serialize_message
from rosbags.interfaces import QosReliability
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore
from sensor_msgs.msg import JointState

from drill_sim.bag import reader
from drill_sim.bag.schema import SEPARATOR, message_definition
from drill_sim.bag.writer import BagError, BagWriter, qos_profile
from drill_sim.wire.rig_topics import OUTPUTS

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)


def _write(path, n=300, **kwargs):
    with BagWriter(path, metadata={"session": {"preset": "base"}}, **kwargs) as w:
        w.add_topic("/rig/bit/wrench", "geometry_msgs/msg/WrenchStamped")
        w.add_topic("/rig/cmd/top_drive", "geometry_msgs/msg/TwistStamped",
                    [qos_profile("best_effort", 5)])
        w.add_topic("/rig/joint_states", "sensor_msgs/msg/JointState")
        for i in range(n):
            t = 1_700_000_000_000_000_000 + i * 10_000_000          # 100 Hz
            m = WrenchStamped()
            m.header.frame_id = "bit"
            m.wrench.force.z = 1000.0 * i
            w.write("/rig/bit/wrench", serialize_message(m), t, t - 1000)
            j = JointState(name=["bit_rotation"], position=[0.1 * i], velocity=[1.0],
                           effort=[2.0])
            w.write("/rig/joint_states", serialize_message(j), t)
            if i % 10 == 0:
                c = TwistStamped()
                c.twist.angular.z = 6.0
                w.write("/rig/cmd/top_drive", serialize_message(c), t)


def test_rosbags_reads_counts_types_qos_and_values(tmp_path):
    bag = tmp_path / "session"
    _write(bag)
    with Reader(bag) as r:
        conns = {c.topic: c for c in r.connections}
        assert {t: c.msgcount for t, c in conns.items()} == {
            "/rig/bit/wrench": 300, "/rig/cmd/top_drive": 30, "/rig/joint_states": 300}
        assert conns["/rig/bit/wrench"].msgtype == "geometry_msgs/msg/WrenchStamped"
        assert conns["/rig/cmd/top_drive"].ext.offered_qos_profiles[0].reliability \
            == QosReliability.BEST_EFFORT
        assert conns["/rig/bit/wrench"].ext.offered_qos_profiles[0].reliability \
            == QosReliability.RELIABLE
        forces = [TYPESTORE.deserialize_cdr(raw, c.msgtype).wrench.force.z
                  for c, _, raw in r.messages() if c.topic == "/rig/bit/wrench"]
        assert forces == [1000.0 * i for i in range(300)]
        assert r.duration == pytest.approx(2.99e9, abs=2)


def test_metadata_yaml_counts_every_message_per_file_and_topic(tmp_path):
    """rosbag2 reads the counts from metadata.yaml (not the MCAP): 300 + 300 + 30 messages."""
    import yaml
    bag = tmp_path / "counted"
    _write(bag)
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["message_count"] == 630
    assert sum(f["message_count"] for f in info["files"]) == 630
    assert {t["topic_metadata"]["name"]: t["message_count"]
            for t in info["topics_with_message_count"]} == {
        "/rig/bit/wrench": 300, "/rig/cmd/top_drive": 30, "/rig/joint_states": 300}


def test_mcap_ros2_support_decodes_every_message_from_the_schema(tmp_path):
    bag = tmp_path / "session"
    _write(bag)
    decoded = list(read_ros2_messages(str(bag / "session_0.mcap")))
    assert len(decoded) == 630
    last = [d for d in decoded if d.channel.topic == "/rig/joint_states"][-1].ros_msg
    assert list(last.position) == [pytest.approx(29.9)]
    header = decoded[0].channel.metadata
    assert header["topic_type_hash"].startswith("RIHS01_")
    assert "reliability: reliable" in header["offered_qos_profiles"]


def test_summary_and_message_indexes_lead_an_indexed_reader_to_every_message(tmp_path):
    """Readers that seek (Foxglove, rosbag2) go through the summary, the chunk indexes and the
    per-chunk message indexes: each index entry must point at a message of its channel and
    time, and the statistics must count what is there."""
    import zstandard
    from mcap.reader import SeekingReader
    from mcap.records import Chunk, MessageIndex
    from mcap.stream_reader import StreamReader, breakup_chunk

    bag = tmp_path / "session"
    _write(bag, n=3000, chunk_size=20_000)                # many chunks
    path = bag / "session_0.mcap"
    with open(path, "rb") as fh:
        r = SeekingReader(fh, validate_crcs=True)
        summary = r.get_summary()
        stats = summary.statistics
        assert stats.message_count == 6300 and len(summary.chunk_indexes) > 10
        by_topic = {summary.channels[k].topic: v for k, v in stats.channel_message_counts.items()}
        assert by_topic == {"/rig/bit/wrench": 3000, "/rig/cmd/top_drive": 300,
                            "/rig/joint_states": 3000}
        later = list(r.iter_messages(topics=["/rig/cmd/top_drive"],
                                     starting_at=1_700_000_000_000_000_000 + 15_000_000_000))
        assert [m.log_time for _, _, m in later][:2] == [
            1_700_000_000_000_000_000 + 15_000_000_000 + k * 100_000_000 for k in range(2)]
        assert len(later) == 150
    checked = 0
    chunk = None
    with open(path, "rb") as fh:
        for rec in StreamReader(fh, emit_chunks=True).records:
            if isinstance(rec, Chunk):
                raw = zstandard.ZstdDecompressor().decompress(rec.data, rec.uncompressed_size)
                chunk = rec
            elif isinstance(rec, MessageIndex):
                for t, offset in rec.records:
                    msg = next(iter(breakup_chunk(Chunk(
                        compression="", data=raw[offset:], message_start_time=0,
                        message_end_time=0, uncompressed_crc=0,
                        uncompressed_size=len(raw) - offset))))
                    assert (msg.channel_id, msg.log_time) == (rec.channel_id, t)
                    assert chunk.message_start_time <= t <= chunk.message_end_time
                    checked += 1
    assert checked == 6300


def test_schema_text_carries_nested_definitions():
    text = message_definition("geometry_msgs/msg/WrenchStamped")
    assert text.count(SEPARATOR) == 4
    for nested in ("MSG: geometry_msgs/Wrench", "MSG: geometry_msgs/Vector3",
                   "MSG: std_msgs/Header", "MSG: builtin_interfaces/Time"):
        assert nested in text


def test_split_by_duration_makes_several_files_read_as_one_bag(tmp_path):
    bag = tmp_path / "split"
    _write(bag, split_duration_s=1.0)
    files = sorted(p.name for p in bag.glob("*.mcap"))
    assert files == ["split_0.mcap", "split_1.mcap", "split_2.mcap"]
    with Reader(bag) as r:
        assert r.message_count == 630


def test_split_by_size_keeps_files_near_the_limit(tmp_path):
    import os

    sized = tmp_path / "split"
    chunk = 16_384
    with BagWriter(sized, split_size_bytes=300_000, chunk_size=chunk) as w:
        w.add_topic("/blob", "std_msgs/msg/UInt8MultiArray")
        for i in range(2000):                           # 2 MB that does not compress
            w.write("/blob", os.urandom(1000), 1_700_000_000_000_000_000 + i * 1_000_000)
    files = sorted(sized.glob("*.mcap"))
    assert len(files) >= 6
    # a file ends with the first message past the limit, plus its summary
    assert all(f.stat().st_size < 300_000 + 2 * chunk + 50_000 for f in files)
    with Reader(sized) as r:
        assert r.message_count == 2000


@pytest.mark.parametrize("fraction", [0.05, 0.3, 0.5, 0.77, 0.9, 0.99, 0.9999])
def test_truncated_bag_is_read_up_to_the_cut_and_repaired(tmp_path, fraction):
    """A file cut anywhere (inside a chunk, an index, the summary) reads up to the cut."""
    bag = tmp_path / "cut"
    _write(bag, n=3000, chunk_size=8192)             # many chunks, as a long session has
    data = (bag / "cut_0.mcap").read_bytes()
    (bag / "cut_0.mcap").write_bytes(data[: int(len(data) * fraction)])
    (bag / "metadata.yaml").unlink()
    found = reader.info(bag)
    assert found.problems and "everything before was read" in found.problems[0]
    assert found.message_count <= 6300
    if fraction >= 0.3:
        assert found.message_count > 6300 * (fraction - 0.2)
    repaired = reader.repair(bag)
    assert repaired.problems == [] and repaired.message_count == found.message_count
    with Reader(bag) as r:
        assert r.message_count == found.message_count


@pytest.mark.offline
def test_foreign_and_corrupt_input_get_clear_messages(tmp_path):
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"this is not an mcap file at all" * 10)
    with pytest.raises(BagError, match="not an MCAP file"):
        reader.info(junk)
    with pytest.raises(BagError, match="no such file"):
        reader.info(tmp_path / "missing")
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(BagError, match=r"no \.mcap file"):
        reader.info(empty)
    with pytest.raises(BagError, match="already exists"):
        BagWriter(empty)
    with pytest.raises(BagError, match=r"folder .*missing does not exist"):   # no parents made
        BagWriter(tmp_path / "missing" / "bag")
    assert not (tmp_path / "missing").exists()
    proc = subprocess.run([installed("drill_sim"), "bag", "info", str(junk)],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "not an MCAP file" in proc.stderr
    assert "Traceback" not in proc.stderr
    proc = subprocess.run([installed("drill_sim"), "bag", "info", str(tmp_path / "missing")],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "no such file" in proc.stderr
    foreign = tmp_path / "foreign"
    _write(foreign, n=20)                     # a bag, but not a session the rig node recorded
    for bag, expected in ((foreign, "no drill_sim session metadata"),
                          (junk, "not an MCAP file")):
        proc = subprocess.run([installed("drill_sim"), "bag", "resim", str(bag)],
                              capture_output=True, text=True, timeout=60)
        assert proc.returncode == 2 and expected in proc.stderr, proc.stderr
        assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("position", [0.02, 0.25, 0.5, 0.75, 0.97])
def test_corrupted_bytes_never_crash_the_reader(tmp_path, position):
    bag = tmp_path / "bad"
    _write(bag, n=2000, chunk_size=8192)
    path = bag / "bad_0.mcap"
    data = bytearray(path.read_bytes())
    at = int(len(data) * position)
    data[at:at + 16] = b"\xff" * 16
    path.write_bytes(bytes(data))
    found = reader.info(bag)                       # reports, never raises
    assert found.problems or found.message_count == 4200
    assert all(p.startswith("bad_0.mcap: ") for p in found.problems)


@pytest.mark.parametrize("position", [0.1, 0.5, 0.9])       # early, middle, late
def test_corrupted_rig_bag_is_read_up_to_the_damage_by_the_fast_paths(tmp_path, position):
    """The memory-mapped walk (replay, resim) and the numpy path (metrics) check each chunk's
    CRC: damaged bytes are skipped with a problem, never a crash or wrong values."""
    from drill_sim.bag.series import rig_series

    bag = tmp_path / "rig"
    samples = rig_bag(bag, 1500, chunk_size=8192)
    path = bag / "rig_0.mcap"
    data = bytearray(path.read_bytes())
    at = int(len(data) * position)
    data[at:at + 16] = bytes(16)
    path.write_bytes(bytes(data))
    problems: list[str] = []
    messages = list(reader.read_messages(bag, problems=problems))
    assert len(messages) <= 1500 * len(OUTPUTS)
    assert problems or len(messages) == 1500 * len(OUTPUTS)
    try:
        series = rig_series(bag)
    except BagError:
        return                                       # a clear refusal is fine
    from bagutil import T0_NS

    from drill_sim.bag.bag import Bag
    from drill_sim.bag.series import VALUE_COLUMN, joint_chunks

    recorded = {T0_NS + round(s.time_s * 1e9): s.wob_n for s in samples}
    with Bag.open(bag) as b:
        chunks = list(joint_chunks(b, "/drill_sim/joint_states", []))
    assert sum(ns.size for ns, _ in chunks) == series.time_s.size
    for ns, values in chunks:               # every sample read is the one recorded then
        assert [recorded[t] for t in ns.tolist()] == values[:, VALUE_COLUMN["wob_n"]].tolist()


@pytest.mark.offline
def test_rig_series_refuses_foreign_or_missing_joint_states(tmp_path):
    from drill_sim.bag.series import rig_series
    bag = tmp_path / "foreign"
    _write(bag, n=20)                              # joint_states with one joint of its own
    with pytest.raises(BagError, match="expected drill_sim's"):
        rig_series(bag)
    with pytest.raises(BagError, match="no sensor_msgs/msg/JointState topic /x"):
        rig_series(bag, "/x")
    proc = subprocess.run([installed("drill_sim"), "bag", "metrics", str(bag)],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "expected drill_sim's" in proc.stderr


@pytest.mark.parametrize("command_every", [0, 7])   # messages at a regular stride, or not
def test_rig_series_through_the_indexes_equals_the_samples_and_survives_a_cut(tmp_path,
                                                                              command_every):
    from drill_sim.bag.series import JOINT_FIELDS, rig_series

    bag = tmp_path / "rig"
    samples = rig_bag(bag, 3000, command_every=command_every)
    series = rig_series(bag)
    assert series.time_s.size == 3000
    for name in JOINT_FIELDS:
        assert np.array_equal(getattr(series, name), [getattr(s, name) for s in samples]), name
    # a crash right after a chunk, before its message indexes: that chunk is walked instead
    from drill_sim.bag.mcap_scan import OP_CHUNK, OP_MESSAGE_INDEX, McapScan

    path = bag / "rig_0.mcap"
    with McapScan(path, []) as scan:
        records = list(scan.records())
    third_chunk_end = [end for op, _, end in records if op == OP_CHUNK][2]
    index_start = min(start - 9 for op, start, _ in records
                      if op == OP_MESSAGE_INDEX and start > third_chunk_end)
    data = path.read_bytes()
    for cut_at in (index_start, len(data) // 2):       # ... and a cut inside a chunk
        path.write_bytes(data[:cut_at])
        cut = rig_series(bag)
        n = cut.time_s.size
        assert 0 < n < 3000            # how many: by the outputs a tick has (chunk size)
        assert np.array_equal(cut.wob_n, [s.wob_n for s in samples[:n]])


@pytest.mark.parametrize("tool", ["info", "metrics", "export", "plot", "diagnostics"])
def test_every_tool_says_the_same_of_a_path_that_is_no_bag(tmp_path, tool, capsys):
    """A text file, an empty file and a device: one line, exit 2, the same words from every
    bag tool (``metrics`` said "no JointState topic" of a text file, and every tool said
    "no such file" of /dev/null)."""
    from drill_sim.cli.main import main
    text = tmp_path / "notes.txt"
    text.write_text("not a bag\n")
    empty = tmp_path / "empty.mcap"
    empty.write_bytes(b"")
    extra = ["--out", str(tmp_path / "out.csv")] if tool in ("export", "plot") else []
    if tool == "plot":
        extra = ["--out", str(tmp_path / "out.png")]
    for path, words in ((text, "not an MCAP file (it does not start with the MCAP magic"),
                        (empty, "not an MCAP file (an empty file)"),
                        (Path("/dev/null"), "not a file or a folder")):
        assert main(["bag", tool, str(path), *extra]) == 2, (tool, path)
        err = capsys.readouterr().err
        assert words in err and len(err.strip().splitlines()) == 1, (tool, path, err)
