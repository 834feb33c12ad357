"""The rig node's output messages as CDR bytes, without ROS: which topics, of which types, in
which order, and one encoder for a whole sample. The node publishes and records these bytes;
tools and benchmarks that make rig bags offline use the same."""

from __future__ import annotations

from ..core.rig import RigSample
from . import cdr

# (topic relative to the node, type) in publishing order; /clock comes first when published
OUTPUTS = (("bit/wrench", "geometry_msgs/msg/WrenchStamped"),
           ("bit/twist", "geometry_msgs/msg/TwistStamped"),
           ("bit/stick_slip", "std_msgs/msg/Bool"),
           ("top_drive/wrench", "geometry_msgs/msg/WrenchStamped"),
           ("bit/depth_of_cut", "std_msgs/msg/Float64"),
           ("bit/hole_depth", "std_msgs/msg/Float64"),
           ("joint_states", "sensor_msgs/msg/JointState"))
CLOCK = ("/clock", "rosgraph_msgs/msg/Clock")
FRAME_BIT, FRAME_TOP_DRIVE = "bit", "top_drive"
JOINT_NAMES = ("top_drive", "hook", "bit_rotation", "bit_axial")


class RigEncoders:
    """CDR encoders of the node's messages, compiled once (frames and joint names fixed)."""

    def __init__(self, with_clock: bool) -> None:
        self.with_clock = with_clock
        self.bit_wrench = cdr.stamped_vectors(FRAME_BIT)
        self.bit_twist = cdr.stamped_vectors(FRAME_BIT)
        self.td_wrench = cdr.stamped_vectors(FRAME_TOP_DRIVE)
        self.flag = cdr.boolean()
        self.float64 = cdr.float64()
        self.joints = cdr.joint_state("", JOINT_NAMES)
        self.clock = cdr.clock()
        self.command = cdr.StampedVectorsByFrame()
        self.event = cdr.string

    def sample(self, stamp_ns: int, s: RigSample) -> list[bytes]:
        """One tick's messages, in the order of OUTPUTS (after /clock if published)."""
        sec, nsec = divmod(stamp_ns, 1_000_000_000)
        data = [
            self.bit_wrench(sec, nsec, (0.0, 0.0, s.wob_n, 0.0, 0.0, s.tob_nm)),
            self.bit_twist(sec, nsec, (0.0, 0.0, s.rop_m_s, 0.0, 0.0, s.bit_speed_rad_s)),
            self.flag(s.stick_slip),
            self.td_wrench(sec, nsec, (0.0, 0.0, s.hook_load_n, 0.0, 0.0,
                                       s.surface_torque_nm)),
            self.float64(s.depth_of_cut_m),
            self.float64(s.hole_depth_m),
            self.joints(sec, nsec,
                        (s.top_drive_angle_rad, s.bit_depth_m, s.bit_angle_rad, s.hole_depth_m),
                        (s.top_drive_speed_rad_s, s.rop_m_s, s.bit_speed_rad_s, s.rop_m_s),
                        (s.surface_torque_nm, s.hook_load_n, s.tob_nm, s.wob_n))]
        if self.with_clock:
            data.insert(0, self.clock(sec, nsec))
        return data
