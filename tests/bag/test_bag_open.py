"""A bag is opened once: one ``Bag`` serves info, topic types, metadata, the message walk and
the rig's series, and each ``drill_sim bag`` tool opens every file of its bag once."""

from __future__ import annotations

import builtins
import collections
from pathlib import Path

import pytest
from bagutil import rig_bag

from drill_sim.bag.bag import Bag
from drill_sim.bag.series import rig_series
from drill_sim.cli.main import main
from drill_sim.wire.rig_topics import OUTPUTS

TICKS = 400
TOPICS = len(OUTPUTS)   # the rig's outputs, one message each per tick


@pytest.fixture
def mcap_opens(monkeypatch) -> collections.Counter:
    """How often each ``.mcap`` file is opened, by name."""
    opens: collections.Counter = collections.Counter()
    real_open = builtins.open

    def counting_open(file, *args, **kwargs):
        if str(file).endswith(".mcap"):
            opens[Path(file).name] += 1
        return real_open(file, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", counting_open)
    return opens


@pytest.mark.parametrize("crashed", [False, True])
def test_one_bag_serves_info_types_metadata_walks_and_series(tmp_path, mcap_opens, crashed):
    bag_dir = tmp_path / "rig"
    samples = rig_bag(bag_dir, TICKS, chunk_size=8192)
    if crashed:                                      # summary gone: every answer walks the file
        path = bag_dir / "rig_0.mcap"
        path.write_bytes(path.read_bytes()[:-60])
    mcap_opens.clear()
    with Bag.open(bag_dir) as bag:
        info = bag.info()
        assert info.message_count == TICKS * TOPICS
        assert bool(info.problems) == crashed
        assert "rosbag2" in bag.metadata
        assert bag.metadata_yaml["message_count"] == TICKS * TOPICS
        assert bag.topic_types()["/drill_sim/joint_states"] == "sensor_msgs/msg/JointState"
        for _ in range(2):                           # a replay loop walks the bag again
            assert sum(1 for _ in bag.messages()) == TICKS * TOPICS
        assert rig_series(bag).time_s.size == len(samples)
    assert mcap_opens == {"rig_0.mcap": 1}


@pytest.mark.parametrize("tool", [["info"], ["metrics", "--json"], ["export", "--out"],
                                  ["plot", "--out"], ["resim"]])
def test_each_bag_tool_opens_the_bag_once(tmp_path, mcap_opens, monkeypatch, capsys, tool):
    bag_dir = tmp_path / "rig"
    rig_bag(bag_dir, 200, chunk_size=8192)
    opened: list[Path] = []
    real_open = Bag.open.__func__

    def counting_open(cls, path):
        opened.append(path)
        return real_open(cls, path)

    monkeypatch.setattr(Bag, "open", classmethod(counting_open))
    mcap_opens.clear()
    argv = ["bag", tool[0], str(bag_dir), *tool[1:]]
    if argv[-1] == "--out":
        argv.append(str(tmp_path / ("out.png" if tool[0] == "plot" else "out.csv")))
    status = main(argv)
    # resim refuses a bag the node did not record, after reading its info
    assert status == (2 if tool[0] == "resim" else 0), capsys.readouterr().err
    assert opened == [bag_dir]
    assert mcap_opens == {"rig_0.mcap": 1}
