"""The rig node's output messages as CDR bytes, without ROS: one encoder per published topic,
compiled from the topics table (``rig_topics``), and one call for a whole sample. The node
publishes and records these bytes; tools and benchmarks that make rig bags offline use the same.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from ..wire import cdr, rig_topics

if TYPE_CHECKING:
    from ..core.rig import RigSample
    from ..core.sensors import Measured


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
