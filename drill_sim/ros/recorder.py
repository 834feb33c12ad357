"""In-node recording: every topic the node publishes and every command it receives, into a
rosbag2 MCAP bag (``drill_sim.bag.writer``), with the session's context as MCAP metadata.
Outputs are recorded as the very bytes the node published; commands and events are encoded
here (``drill_sim.wire.cdr``).

Recording problems (full disk, unwritable path) stop the recording with a clear error and leave
the simulation running; the bag written so far stays readable.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from .. import __version__
from ..bag.writer import BagError, BagWriter
from ..wire import WireError, cdr
from ..wire.qos import qos_profile


class SessionRecorder:
    def __init__(self, path: str, topics: dict[str, tuple[str, str]], *, reliability: str,
                 context: dict[str, dict[str, str]], logger, split_duration_s: float = 0.0,
                 split_size_bytes: int = 0) -> None:
        """topics: full topic name -> (type name pkg/msg/Type, reliability)."""
        self.logger = logger
        self.error: str | None = None
        meta = {"session": {"package": "drill_sim", "version": __version__,
                            "start_time_ns": str(time.time_ns()),
                            "command_line": json.dumps(sys.argv)}}
        for name, values in context.items():
            meta.setdefault(name, {}).update(values)
        self.writer = BagWriter(Path(path), metadata=meta, split_duration_s=split_duration_s,
                                split_size_bytes=split_size_bytes)
        for name, (type_name, rel) in topics.items():
            self.writer.add_topic(name, type_name, [qos_profile(rel or reliability)])
        self._encode_command = cdr.StampedVectorsByFrame()

    def record_command(self, topic: str, frame_id: str, sec: int, nanosec: int,
                       six: tuple[float, ...]) -> None:
        """A command as received (TwistStamped or WrenchStamped, its six float64), logged now
        and published at its stamp (now if stamped before 1970: that cannot be a time)."""
        if self.error is None:
            now, sent = time.time_ns(), sec * 1_000_000_000 + nanosec
            try:
                self.writer.write(topic, self._encode_command(frame_id, sec, nanosec, six), now,
                                  sent if sent >= 0 else now)
            except (OSError, BagError, WireError) as exc:
                self._stop(exc)

    def record_event(self, topic: str, text: str) -> None:
        """A session event (std_msgs/String), logged and published now."""
        if self.error is None:
            now = time.time_ns()
            try:
                self.writer.write(topic, cdr.string(text), now, now)
            except (OSError, BagError, WireError) as exc:
                self._stop(exc)

    def record_many(self, topics: list[str], data: list[bytes], time_ns: int) -> None:
        """One tick's outputs, all received and published at ``time_ns``."""
        if self.error is None:
            write = self.writer.write
            try:
                for topic, raw in zip(topics, data, strict=True):
                    write(topic, raw, time_ns, time_ns)
            except (OSError, BagError) as exc:
                self._stop(exc)

    def _stop(self, exc: Exception) -> None:
        self.error = f"recording stopped: {exc}"
        self.logger.error(self.error + "; the simulation keeps running")
        try:
            self.writer.close()
        except (OSError, BagError):
            pass

    def close(self) -> None:
        if self.error is None:
            try:
                self.writer.close()
            except (OSError, BagError) as exc:
                self.logger.error(f"closing the bag failed: {exc}")
