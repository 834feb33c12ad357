"""Gaps in a publisher's sequence numbers (``bag.losses``): exact counts between received
messages, nothing counted where the numbers cannot tell (several publishers, a publisher
starting again), and the record a bag keeps of them."""

from __future__ import annotations

import json

from drill_sim.bag.losses import SequenceGaps


def test_each_jump_is_the_messages_between_and_when():
    gaps = SequenceGaps()
    for seq, t in ((1, 0.0), (2, 0.1), (5, 0.2), (6, 0.3), (106, 0.9)):
        gaps.note("/a", seq, t)
    gaps.note("/b", 7, 0.5)                        # first message of /b: nothing to compare
    assert [(g.topic, g.count, g.after_s, g.before_s) for g in gaps.gaps] == [
        ("/a", 2, 0.1, 0.2), ("/a", 99, 0.3, 0.9)]
    assert gaps.lost == 101 and gaps.lost_by_topic() == {"/a": 101}
    assert gaps.gaps[0].line() == ("lost 2 on /a between t = 0.100 and 0.200 s of the "
                                   "recording")
    record = gaps.record()
    assert record["lost_messages"] == "101"
    assert json.loads(record["gaps"]) == [["/a", 2, 0.1, 0.2], ["/a", 99, 0.3, 0.9]]
    assert json.loads(record["first_sequence_by_topic"]) == {"/a": 1, "/b": 7}
    assert all(isinstance(v, str) for v in record.values())


def test_several_publishers_a_restart_or_no_numbers_count_nothing():
    gaps = SequenceGaps()
    gaps.note("/a", 10, 0.0)
    gaps.note("/a", 20, 0.1, publishers=2)         # interleaved numbering of two writers
    gaps.note("/a", 1, 0.2)                        # a publisher starting again
    gaps.note("/a", 2, 0.3)
    gaps.note("/c", None, 0.0)                     # a middleware that numbers nothing
    gaps.note("/c", 0, 0.1)
    assert gaps.lost == 0 and gaps.gaps == []
    assert gaps.uncounted == {"/a"}
    assert json.loads(gaps.record()["loss_not_counted_on"]) == ["/a"]
