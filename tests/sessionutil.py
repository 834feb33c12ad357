"""Rig bags made for tests without ROS: a sim-time session as the node records it (parameters
and session metadata, so ``bag resim`` can re-run it), and a rig bag from given samples."""

from __future__ import annotations

import math
from collections.abc import Iterable

from drill_sim.bag.writer import BagWriter
from drill_sim.core import RigSample, load_preset
from drill_sim.core.sensors import session_sensors
from drill_sim.ros.parameters import specs
from drill_sim.session import rules
from drill_sim.session.rig_messages import RigEncoders

WALL0_NS = 1_700_000_000_000_000_000


def session_bag(path, ticks: int, *, rate_hz: float = 100.0, speedup: float = 10.0,
                node: str = "/drill_sim", chunk_size: int = 8192,
                recorded_step: bool = True) -> None:
    """A sim-time session of the base preset as the node records it: stamps count simulated
    time from 0, log times are the wall clock running ``speedup`` times slower.
    recorded_step False: as the node recorded before its step divided the tick (stepping at
    ``dt_s`` itself, the step not in the metadata)."""
    p = {s.name: s.default for s in specs(load_preset("base"))}
    p.update(publish_clock=True, rate_hz=rate_hz, max_speed=True, record=str(path))
    rig = rules.make_rig(p, None if recorded_step else p["dt_s"])
    rules.start(rig, p)
    sensors = session_sensors(p, rig.dt_s)
    meta = {"parameters": {k: str(v) for k, v in sorted(p.items())},
            "session": {"preset": "base", "node": node, "stamp_epoch_ns": "0",
                        "events_topic": f"{node}/events"}}
    if recorded_step:
        meta["session"]["step_s"] = repr(rig.dt_s)
    enc = RigEncoders(with_clock=False)
    topics = [t.under(node) for t in enc.topics]
    with BagWriter(path, metadata=meta, chunk_size=chunk_size,
                   flush_interval_s=math.inf) as w:
        for topic, t in zip(topics, enc.topics, strict=True):
            w.add_topic(topic, t.type_name)
        w.add_topic(f"{node}/events", "std_msgs/msg/String")
        for k in range(1, ticks + 1):
            rig.advance_to(k / rate_hz)
            stamp = round(rig.time_s * 1e9)
            log = WALL0_NS + round(stamp / speedup)
            s = rig.sample()
            data = enc.sample(stamp, s, sensors.measure(rig.time_s, s))
            for topic, message in zip(topics, data, strict=True):
                w.write(topic, message, log)


def samples_bag(path, stamped: Iterable[tuple[int, RigSample]], *,
                prefix: str = "/drill_sim") -> None:
    """A rig bag of the given (header stamp [ns], sample) pairs, logged at their stamps."""
    enc = RigEncoders(with_clock=False)
    topics = [t.under(prefix) for t in enc.topics]
    with BagWriter(path, chunk_size=8192, flush_interval_s=math.inf) as w:
        for topic, t in zip(topics, enc.topics, strict=True):
            w.add_topic(topic, t.type_name)
        for stamp, s in stamped:
            for topic, data in zip(topics, enc.sample(stamp, s), strict=True):
                w.write(topic, data, max(stamp, 0))
