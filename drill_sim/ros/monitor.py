"""A subscriber that collects the rig's ``~/joint_states`` for live status, summary and plots."""

from __future__ import annotations

import numpy as np
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool

from . import interface as itf

# columns of Monitor.samples(): time [s], top-drive speed [rad/s], bit speed [rad/s], ROP [m/s],
# WOB [N], TOB [N m], surface torque [N m], hook load [N], hole depth [m], stick-slip flag
COLUMNS = ("time_s", "top_drive_speed_rad_s", "bit_speed_rad_s", "rop_m_s", "wob_n", "tob_nm",
           "surface_torque_nm", "hook_load_n", "hole_depth_m", "stick_slip")


class Monitor(Node):
    def __init__(self, rig: str = itf.NODE_NAME, capacity: int = 4_000_000) -> None:
        super().__init__("drill_sim_monitor")
        q = itf.qos("reliable", depth=1000)
        self.create_subscription(JointState, f"{rig}/joint_states", self._on_joints, q)
        self.create_subscription(Bool, f"{rig}/bit/stick_slip", self._on_flag, q)
        self._data = np.zeros((capacity, len(COLUMNS)))
        self.count = 0
        self.flag = False

    def _on_flag(self, msg: Bool) -> None:
        self.flag = msg.data

    def _on_joints(self, msg: JointState) -> None:
        if self.count >= self._data.shape[0] or len(msg.position) != 4:
            return
        p, v, e = msg.position, msg.velocity, msg.effort
        t = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        self._data[self.count] = (t, v[0], v[2], v[3], e[3], e[2], e[0], e[1], p[3], self.flag)
        self.count += 1

    def samples(self) -> np.ndarray:
        return self._data[:self.count]

    def latest(self) -> dict[str, float] | None:
        if self.count == 0:
            return None
        return dict(zip(COLUMNS, self._data[self.count - 1], strict=True))
