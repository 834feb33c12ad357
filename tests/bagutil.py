"""Bags made for tests: a rig session written as the node records it."""

from __future__ import annotations

import math
import struct

from geometry_msgs.msg import TwistStamped
from rclpy.serialization import serialize_message

from drill_sim.bag.mcap_scan import OP_CHUNK, OP_MESSAGE_INDEX, McapScan
from drill_sim.bag.writer import BagWriter
from drill_sim.core import RPM, Rig, RigSample, load_preset
from drill_sim.session.rig_messages import RigEncoders

T0_NS = 1_700_000_000_000_000_000


def rig_bag(path, ticks: int, *, prefix: str = "/drill_sim", command_every: int = 0,
            chunk_size: int = 30_000, rate_hz: float = 1000.0) -> list[RigSample]:
    """A bag as the node records it (same encoders, same writer) from the base rig in
    stick-slip, ``ticks`` ticks at ``rate_hz``; a top-drive command every ``command_every``
    ticks if given. Chunks close by size only, so their boundaries do not depend on the
    machine's speed. Returns the samples written."""
    preset = load_preset("base")
    rig = Rig(preset.rig)
    rig.start_steady(60 * RPM, preset.rig.submerged_weight_n - 100e3)
    enc = RigEncoders(with_clock=False)
    topics = [t.under(prefix) for t in enc.topics]
    samples = []
    with BagWriter(path, chunk_size=chunk_size, flush_interval_s=math.inf) as w:  # by size only
        for topic, t in zip(topics, enc.topics, strict=True):
            w.add_topic(topic, t.type_name)
        w.add_topic(f"{prefix}/cmd/top_drive", "geometry_msgs/msg/TwistStamped")
        for k in range(1, ticks + 1):
            rig.advance_to(k / rate_hz)
            s = rig.sample()
            samples.append(s)
            stamp = T0_NS + round(s.time_s * 1e9)
            for topic, data in zip(topics, enc.sample(stamp, s), strict=True):
                w.write(topic, data, stamp)
            if command_every and k % command_every == 0:
                w.write(f"{prefix}/cmd/top_drive", serialize_message(TwistStamped()), stamp)
    return samples


def chunk_spans(path) -> list[tuple[int, int, int]]:
    """(record start, body end, messages from its indexes) of every chunk of an MCAP file."""
    found: list[list[int]] = []
    with McapScan(path, []) as scan:
        for op, start, end in scan.records():
            if op == OP_CHUNK:
                found.append([start - 9, end, 0])
            elif op == OP_MESSAGE_INDEX:
                found[-1][2] += struct.unpack_from("<I", scan.view, start + 2)[0] // 16
    return [tuple(c) for c in found]
