"""The rig node's output messages as CDR bytes, without ROS: one encoder per published topic,
compiled from the topics table (``rig_topics``), and one call for a whole sample; and a tick's
outputs (``TickOutputs``): which are live, measured and encoded once, sent and recorded. The node
publishes and records these bytes; tools and benchmarks that make rig bags offline use the same.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from ..core.sensor_profile import CHANNELS
from ..wire import cdr, rig_topics

if TYPE_CHECKING:
    from ..core.rig_sample import RigSample
    from ..core.sensors import Measured, SensorBank
    from .recorder import SessionRecorder

Send = Callable[[bytes], object]


class RigEncoders:
    """CDR encoders of the messages the node publishes every tick, compiled once from the
    table (frames and joint names fixed); ``topics`` in the order ``sample`` returns them."""

    def __init__(self, with_clock: bool) -> None:
        self.with_clock = with_clock
        self.topics = rig_topics.published(with_clock)
        self._encoders = [
            cdr.fields_encoder(cdr.layout(t.type_name, frame_id=t.frame_id, names=t.joints),
                               [(f.message, f.sample) for f in t.fields])
            for t in self.topics]
        self._measured = [t.source == rig_topics.MEASURED for t in self.topics]
        self.measured = tuple(self._measured)    # which topics show the sensors (``m``)

    def sample(self, stamp_ns: int, s: RigSample, m: Measured | None = None) -> list[bytes]:
        """One tick's messages stamped ``stamp_ns`` [ns], in the order of ``topics``: the
        exact ones from ``s``, the ``~/measured/`` ones from ``m`` (None: the ideal sensors'
        reading of ``s``, ``core.sensors.exact_measured``)."""
        return self.some(stamp_ns, s, m, range(len(self._encoders)))

    def some(self, stamp_ns: int, s: RigSample, m: Measured | None,
             at: Sequence[int]) -> list[bytes]:
        """The messages of the topics at ``at`` (indices into ``topics``), in that order,
        as ``sample`` makes them: the node encodes only the outputs it publishes (walking
        all 16 encoders with a flag each cost ~4 us a tick more). ``m`` is needed (or made
        from ``s``) only if one of them is a ``~/measured/`` topic."""
        encoders, measured = self._encoders, self._measured
        if m is None and any(measured[k] for k in at):
            from ..core.sensors import exact_measured
            m = exact_measured(s)
        sec, nsec = divmod(stamp_ns, 1_000_000_000)
        return [encoders[k](sec, nsec, m if measured[k] else s) for k in at]


class TickOutputs:
    """A tick's outputs: which are live (published; not recording, the only ones encoded),
    and one sample measured and encoded once into the bytes every live output sends and the
    recorder keeps. ``on_sample``: a ``~/measured/`` output none of whose channels took a
    fresh value is neither sent nor recorded (``measured_publish:=on_sample``)."""

    def __init__(self, with_clock: bool, on_sample: bool) -> None:
        self.encoders = RigEncoders(with_clock)
        self.topics = self.encoders.topics
        self.on_sample = on_sample
        measured = self.encoders.measured
        # each ~/measured/ output's channels (indices into the sensors' CHANNELS)
        self._channels_of = [(k, tuple(CHANNELS.index(f.sample) for f in t.fields))
                             for k, t in enumerate(self.topics) if measured[k]]
        self.set_live([True] * len(self.topics))

    def set_live(self, live: Sequence[bool]) -> None:
        """Which outputs are published; their places, exact and measured apart."""
        measured = self.encoders.measured
        self._live_at = [k for k, on in enumerate(live) if on]
        self._live_exact_at = [k for k in self._live_at if not measured[k]]
        self._live_measured_at = [k for k in self._live_at if measured[k]]

    def emit(self, stamp_ns: int, s: RigSample, sensors: SensorBank, time_s: float,
             recorder: SessionRecorder | None, send: Sequence[Send]) -> Measured:
        """Sample ``s`` stamped ``stamp_ns``, measured by ``sensors`` at ``time_s``: each live
        output's bytes to ``send[k]``, the same bytes to ``recorder``; the reading.

        Not recording, the exact outputs are sent before the sensors measure (every tick:
        their state goes on whether or not anyone listens), then the measured ones: the same
        order (the table lists ``~/measured/`` last), but a lockstep controller that reads
        exact outputs gets them ~15 us sooner and works while the node measures."""
        enc = self.encoders
        if recorder is None:
            at = self._live_exact_at
            for k, raw in zip(at, enc.some(stamp_ns, s, None, at), strict=True):
                send[k](raw)
            m = sensors.measure(time_s, s)
            if self.on_sample and (held := self._held(m)):
                at = [k for k in self._live_measured_at if k not in held]
            else:
                at = self._live_measured_at
            if at:
                for k, raw in zip(at, enc.some(stamp_ns, s, m, at), strict=True):
                    send[k](raw)
            return m
        m = sensors.measure(time_s, s)
        data = enc.sample(stamp_ns, s, m)
        held = self._held(m) if self.on_sample else ()
        for k in self._live_at:
            if k not in held:
                send[k](data[k])
        recorder.record_outputs(data, held)
        return m

    def again(self, last: tuple[int, RigSample, Measured], send: Sequence[Send]) -> None:
        """A sample's outputs sent again to every output (not recorded again)."""
        for k, raw in enumerate(self.encoders.sample(*last)):
            send[k](raw)

    def _held(self, m: Measured) -> tuple[int, ...]:
        fresh = m.fresh
        return tuple(k for k, channels in self._channels_of if not any(fresh[c] for c in channels))
