"""drill_sim_record and drill_sim_replay, run as installed commands in their own processes."""

from __future__ import annotations

import itertools
import json
import struct
import subprocess
import time

import pytest
from bagutil import rig_bag
from conftest import installed
from geometry_msgs.msg import TwistStamped
from rclpy.duration import Duration
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from rosbags.interfaces import QosReliability
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore
from rosgraph_msgs.msg import Clock
from rosutil import NodeProcess, wait_for
from std_msgs.msg import Float64

from drill_sim.bag.bag import Bag
from drill_sim.bag.reader import read_messages
from drill_sim.bag.writer import BagWriter, qos_profile

T0 = 1_700_000_000_000_000_000
RELIABLE = QoSProfile(depth=5000, reliability=ReliabilityPolicy.RELIABLE)
TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
FLOAT64 = struct.Struct("<4sd")


def _stream_bag(path, prefix: str, n: int = 2000) -> None:
    """n numbered Float64 at 1 kHz on {prefix}/stream, a 10 Hz best-effort command beside."""
    with BagWriter(path) as w:
        w.add_topic(f"{prefix}/stream", "std_msgs/msg/Float64")
        w.add_topic(f"{prefix}/cmd", "geometry_msgs/msg/TwistStamped",
                    [qos_profile("best_effort", 5)])
        for i in range(n):
            t = T0 + i * 1_000_000
            w.write(f"{prefix}/stream", FLOAT64.pack(b"\x00\x01\x00\x00", float(i)), t)
            if i % 100 == 0:
                w.write(f"{prefix}/cmd", serialize_message(TwistStamped()), t)


class _Received:
    """Numbers and arrival times from a raw Float64 subscription."""

    def __init__(self, node, topic: str) -> None:
        self.values: list[float] = []
        self.times: list[float] = []
        self.sub = node.create_subscription(Float64, topic, self._on, RELIABLE, raw=True)

    def _on(self, data: bytes) -> None:
        self.values.append(FLOAT64.unpack(data)[1])
        self.times.append(time.monotonic())


def _finish(proc: NodeProcess, timeout_s: float = 60.0) -> str:
    """Let the player end on its own; its exit status and output."""
    out, _ = proc.proc.communicate(timeout=timeout_s)
    assert proc.proc.returncode == 0, out
    return out


@pytest.mark.parametrize("rate", [1.0, 10.0])
def test_replay_loses_no_message_and_keeps_the_timing(ros, tmp_path, rate):
    prefix = f"/replay_{int(rate)}x"
    _stream_bag(tmp_path / "bag", prefix)
    # the player starts first and must wait for the subscriber, not play into the void
    with NodeProcess("drill_sim_replay", str(tmp_path / "bag"), "--rate", str(rate)) as player:
        got = _Received(ros, f"{prefix}/stream")
        wait_for(lambda: len(got.values) >= 2000 or player.proc.poll() is not None, ros, 60,
                 "2000 replayed messages")
        out = _finish(player)
    wait_for(lambda: len(got.values) >= 2000, ros, 10, "the last replayed messages")
    assert got.values == [float(i) for i in range(2000)], out
    span = got.times[-1] - got.times[0]
    assert span >= 0.95 * 1.999 / rate          # never ahead of the recorded timing
    assert span < 5.0 * 1.999 / rate + 2.0      # nor far behind it (a loaded machine lags)
    assert "published 2020 messages" in out


@pytest.mark.parametrize("rate", [2.0, 5.0])
def test_a_rig_session_replayed_into_the_recorder_comes_back_byte_for_byte(ros, tmp_path,
                                                                           rate):
    """A second and a half of a rig session (every output topic at 1 kHz, 1500 messages each)
    replayed faster than recorded into drill_sim_record with the defaults: every message
    arrives, in order, with the same bytes, read back by another reader; the recorder says
    none was lost. The player waits until the recorder has subscribed to every topic (it
    discovers them one by one); both keep every message in their histories, so a recorder
    that falls behind (a busy core) holds the player back instead of losing messages."""
    rig_bag(tmp_path / "session", 1500, prefix="/twox")
    recorded = tmp_path / "recorded"
    with NodeProcess("drill_sim_record", "-e", "^/twox/", "-o", str(recorded)) as rec:
        run = subprocess.run([installed("drill_sim_replay"), str(tmp_path / "session"),
                              "--rate", str(rate), "--wait-for", "all"], capture_output=True,
                             text=True, timeout=120)
        assert run.returncode == 0, run.stderr
        code, out = rec.stop()
    assert code == 0, out
    assert "none lost" in out, out

    def by_topic(bag):
        found: dict[str, list[bytes]] = {}
        for m in read_messages(bag):
            found.setdefault(m.topic, []).append(m.data)
        return found

    original, copy = by_topic(tmp_path / "session"), by_topic(recorded)
    assert {t: len(v) for t, v in copy.items()} == {t: len(v) for t, v in original.items()}
    assert copy == original


def test_replay_can_wait_for_a_subscription_on_every_topic(ros, tmp_path):
    """--wait-for all: one subscription on every topic played before playing; after
    --wait-timeout the player names the topics nobody subscribed to and plays anyway. (The
    timeout is long enough for a loaded machine to discover the one subscription there is:
    with 3 s the player once played before it saw it, and the messages went to nobody.)"""
    _stream_bag(tmp_path / "bag", "/every", n=200)
    got = _Received(ros, "/every/stream")              # nobody on /every/cmd
    started = time.monotonic()
    with NodeProcess("drill_sim_replay", str(tmp_path / "bag"), "--wait-for", "all",
                     "--wait-timeout", "8") as player:
        wait_for(lambda: player.proc.poll() is not None, ros, 60, "the player to finish")
        out = _finish(player)
    wait_for(lambda: len(got.values) >= 200, ros, 10, "the replayed messages")
    assert got.values == [float(i) for i in range(200)], out
    assert got.times[0] - started >= 8.0                # it waited for the timeout
    assert "none on 1 topics (/every/cmd)" in out and "playing anyway" in out


def test_replay_start_offset_topic_filter_and_clock(ros, tmp_path):
    _stream_bag(tmp_path / "bag", "/offset")
    clock: list[int] = []
    ros.create_subscription(Clock, "/clock", lambda m: clock.append(
        m.clock.sec * 1_000_000_000 + m.clock.nanosec), 100)
    cmds: list[object] = []
    ros.create_subscription(TwistStamped, "/offset/cmd", cmds.append, 10)
    with NodeProcess("drill_sim_replay", str(tmp_path / "bag"), "--rate", "4",
                     "--start-offset", "1.0", "--topics", "/offset/stream",
                     "--clock", "200") as player:
        got = _Received(ros, "/offset/stream")
        wait_for(lambda: player.proc.poll() is not None, ros, 60, "the player to finish")
        out = _finish(player)
    wait_for(lambda: len(got.values) >= 1000, ros, 10, "the replayed messages")
    assert got.values == [float(i) for i in range(1000, 2000)], out
    assert cmds == []
    assert len(clock) >= 10
    assert all(b >= a for a, b in itertools.pairwise(clock))
    assert T0 + 1_000_000_000 <= clock[0] and clock[-1] <= T0 + 2_000_000_000


def test_replay_plays_a_bag_written_by_another_tool_onto_a_remapped_topic(ros, tmp_path):
    bag = tmp_path / "foreign"
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = w.add_connection("/foreign/value", "std_msgs/msg/Float64", typestore=TYPESTORE)
        msg_type = TYPESTORE.types["std_msgs/msg/Float64"]
        for i in range(300):
            w.write(conn, T0 + i * 10_000_000,
                    TYPESTORE.serialize_cdr(msg_type(data=float(i)), "std_msgs/msg/Float64"))
    with NodeProcess("drill_sim_replay", str(bag), "--rate", "10", "--ros-args", "-r",
                     "/foreign/value:=/foreign/renamed") as player:
        got = _Received(ros, "/foreign/renamed")
        wait_for(lambda: player.proc.poll() is not None, ros, 60, "the player to finish")
        out = _finish(player)
    wait_for(lambda: len(got.values) >= 300, ros, 10, "the replayed messages")
    assert got.values == [float(i) for i in range(300)], out


@pytest.mark.parametrize("args, expected", [
    (["{tmp}/nowhere"], "no such file or directory"),
    (["{tmp}/bag", "--rate", "0"], "-r/--rate 0: out of range; expected a playback speed"),
    (["{tmp}/bag", "--rate", "nan"], "-r/--rate nan: not a finite number"),
    (["{tmp}/bag", "--topics", "/absent"], "not in"),
    (["{tmp}/bag", "--start-offset", "5"], "past the bag's end"),
    (["{tmp}/junk.mcap"], "not an MCAP file"),
])
def test_replay_bad_input_gets_one_clear_line(tmp_path, args, expected):
    _stream_bag(tmp_path / "bag", "/bad", n=10)
    (tmp_path / "junk.mcap").write_bytes(b"this is no bag at all" * 10)
    run = subprocess.run([installed("drill_sim_replay"),
                          *(a.format(tmp=tmp_path) for a in args), "--wait-for", "0"],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 2, run.stderr
    assert expected in run.stderr
    assert "Traceback" not in run.stderr


def test_record_captures_selected_topics_raw_with_their_qos(ros, tmp_path):
    bag = tmp_path / "rec"
    with NodeProcess("drill_sim_record", "--regex", "^/rec/", "-o", str(bag)) as rec:
        a = ros.create_publisher(Float64, "/rec/a", RELIABLE)
        b = ros.create_publisher(TwistStamped, "/rec/b",
                                 QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
        other = ros.create_publisher(Float64, "/elsewhere", 10)
        wait_for(lambda: a.get_subscription_count() and b.get_subscription_count(), ros, 30,
                 "the recorder to subscribe")
        for i in range(500):
            a.publish(Float64(data=float(i)))
            other.publish(Float64(data=-1.0))
        cmd = TwistStamped()
        cmd.twist.angular.z = 6.0
        b.publish(cmd)
        assert a.wait_for_all_acked(Duration(seconds=30))
        code, out = rec.stop()
    assert code == 0, out
    with Reader(bag) as r:
        conns = {c.topic: c for c in r.connections}
        assert set(conns) == {"/rec/a", "/rec/b"}
        assert conns["/rec/a"].msgcount == 500
        assert conns["/rec/b"].msgtype == "geometry_msgs/msg/TwistStamped"
        assert conns["/rec/b"].ext.offered_qos_profiles[0].reliability \
            == QosReliability.BEST_EFFORT
        values = [TYPESTORE.deserialize_cdr(raw, c.msgtype).data
                  for c, _, raw in r.messages() if c.topic == "/rec/a"]
    assert values == [float(i) for i in range(500)]
    assert "none lost" in out, out
    with Bag.open(bag) as b:
        assert b.metadata["recording"]["lost_messages"] == "0"


def test_record_reports_exactly_the_messages_it_never_received(ros, tmp_path):
    """A recorder frozen (SIGSTOP) while a publisher keeping the last 1000 sends 20 000, with a
    history of one message on the recorder's side: messages are overwritten before the
    recorder takes them, whatever the machine's speed. Every gap it reports (printed, and in
    the bag's metadata) is exactly a gap in the numbers the bag holds, read back by another
    library."""
    import os
    import signal
    bag = tmp_path / "rec"
    with NodeProcess("drill_sim_record", "/gaps/a", "--queue-depth", "1", "-o", str(bag)) as rec:
        a = ros.create_publisher(Float64, "/gaps/a",
                                 QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
        wait_for(lambda: a.get_subscription_count(), ros, 30, "the recorder to subscribe")
        for i in range(100):                    # some before the freeze: gaps come after them
            a.publish(Float64(data=float(i)))
        assert a.wait_for_all_acked(Duration(seconds=30))
        os.kill(rec.proc.pid, signal.SIGSTOP)
        try:
            for i in range(100, 20_000):
                a.publish(Float64(data=float(i)))
        finally:
            os.kill(rec.proc.pid, signal.SIGCONT)
        assert a.wait_for_all_acked(Duration(seconds=30))
        code, out = rec.stop()
    assert code == 0, out
    with Reader(bag) as r:
        values = [int(TYPESTORE.deserialize_cdr(raw, c.msgtype).data)
                  for c, _, raw in r.messages()]
    expected = [b - a - 1 for a, b in itertools.pairwise(values) if b > a + 1]
    assert expected, "the recorder kept up: no gap to report"
    with Bag.open(bag) as b:
        recording = b.metadata["recording"]
    gaps = json.loads(recording["gaps"])
    assert [g[1] for g in gaps] == expected
    assert all(g[0] == "/gaps/a" and g[2] <= g[3] for g in gaps)
    assert int(recording["lost_messages"]) == sum(expected)
    # the publisher numbers its messages from 1: the first one kept is value + 1
    assert json.loads(recording["first_sequence_by_topic"]) == {"/gaps/a": values[0] + 1}
    assert f"LOST {sum(expected)} messages" in out, out
    assert f"lost {expected[0]} on /gaps/a between t = " in out, out
    info = subprocess.run([installed("drill_sim"), "bag", "info", str(bag)],
                          capture_output=True, text=True, timeout=60)
    assert f"Lost in recording: {sum(expected)} messages never reached the recorder" \
        in info.stdout, info.stdout


def test_record_refuses_an_existing_bag_and_bad_arguments(tmp_path):
    (tmp_path / "taken").mkdir()
    for args, expected in ((["/x", "-o", str(tmp_path / "taken")], "it exists already"),
                           ([], "name topics, or give --regex or --all"),
                           (["--regex", "("], "bad regular expression")):
        run = subprocess.run([installed("drill_sim_record"), *args], capture_output=True,
                             text=True, timeout=60)
        assert run.returncode == 2, run.stderr
        assert expected in run.stderr
