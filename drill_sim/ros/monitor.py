"""A subscriber that collects the rig's ``~/joint_states`` (and stick-slip flag) for the live
status line, the summary and the plot of ``drill_sim run``."""

from __future__ import annotations

import numpy as np
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool

from ..bag.series import JOINT_FIELDS, RigSeries
from ..wire import rig_topics
from ..wire.qos import RELIABLE
from .topics import publisher_names, rclpy_qos


class Monitor(Node):
    def __init__(self, rig: str = rig_topics.NODE_NAME) -> None:
        super().__init__("drill_sim_monitor")
        joints, flag = rig_topics.JOINT_STATES, rig_topics.BIT_STICK_SLIP
        self.topic = self.resolve_topic_name(joints.under(rig))
        self.create_subscription(JointState, self.topic, self._on_joints,
                                 rclpy_qos(joints.qos_for(RELIABLE).with_depth(1000)))
        self.create_subscription(Bool, flag.under(rig), self._on_flag,
                                 rclpy_qos(flag.qos_for(RELIABLE).with_depth(1000)))
        # one row per sample: stamp [s], position[4], velocity[4], effort[4], flag; grows x2
        self._rows = np.zeros((1 << 16, 14))
        self.count = 0
        self.flag = False

    def other_rigs(self, first_included: bool = False) -> list[str]:
        """The publishers on the rig's ``~/joint_states`` beyond the session's own rig (fully
        qualified node names): another rig of the same name on this domain, or a replay onto
        it; ``first_included``: all of them (before the session's rig has started)."""
        names = sorted(publisher_names(self.get_publishers_info_by_topic(self.topic)))
        rig = self.topic.rsplit("/", 1)[0]               # the rig this session started
        if first_included:
            return names
        if rig in names:
            names.remove(rig)
            return names
        return names[1:]

    def _on_flag(self, msg: Bool) -> None:
        self.flag = msg.data

    def _on_joints(self, msg: JointState) -> None:
        if len(msg.position) != 4 or len(msg.velocity) != 4 or len(msg.effort) != 4:
            return
        if self.count == self._rows.shape[0]:
            self._rows = np.concatenate([self._rows, np.zeros_like(self._rows)])
        row = self._rows[self.count]
        row[0] = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        row[1:5], row[5:9], row[9:13], row[13] = msg.position, msg.velocity, msg.effort, self.flag
        self.count += 1

    def series(self) -> RigSeries:
        """What was received so far, as the same series ``drill_sim bag`` reads from a bag."""
        r = self._rows[:self.count]
        return RigSeries.from_joints(self.topic, r[:, 0], r[:, 1:5], r[:, 5:9], r[:, 9:13])

    def flags(self) -> np.ndarray:
        return self._rows[:self.count, 13] > 0.0

    def recent(self, seconds: float) -> RigSeries:
        """The samples of the last ``seconds`` of simulated time received."""
        r = self._rows[:self.count]
        first = int(np.searchsorted(r[:, 0], r[-1, 0] - seconds)) if self.count else 0
        r = r[first:]
        return RigSeries.from_joints(self.topic, r[:, 0], r[:, 1:5], r[:, 5:9], r[:, 9:13])

    def latest(self) -> dict[str, float] | None:
        """The last sample by quantity name, plus ``elapsed_s`` and ``stick_slip``."""
        if self.count == 0:
            return None
        row = self._rows[self.count - 1]
        arrays = {"position": row[1:5], "velocity": row[5:9], "effort": row[9:13]}
        out = {name: float(arrays[kind][j]) for name, (kind, j) in JOINT_FIELDS.items()}
        out["elapsed_s"] = float(row[0] - self._rows[0, 0])
        out["stick_slip"] = bool(row[13])
        return out
