"""Names, frames and QoS of the rig node's interface, shared by the node, driver and tools.

All names are node-relative (``~/...``) so ``-r __ns:=/rig1`` namespaces a whole rig.
"""

from __future__ import annotations

from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

from ..bag import rig_messages

NODE_NAME = "drill_sim"

# inputs
CMD_TOP_DRIVE = "~/cmd/top_drive"      # geometry_msgs/TwistStamped, twist.angular.z: Omega0 [rad/s]
CMD_HOOK_LOAD = "~/cmd/hook_load"      # geometry_msgs/WrenchStamped, wrench.force.z = H0 [N]

# outputs, every tick
BIT_WRENCH = "~/bit/wrench"            # WrenchStamped: force.z WOB [N], torque.z TOB [N m]
BIT_TWIST = "~/bit/twist"              # TwistStamped: linear.z axial speed [m/s], angular.z [rad/s]
BIT_STICK_SLIP = "~/bit/stick_slip"    # std_msgs/Bool
BIT_DEPTH_OF_CUT = "~/bit/depth_of_cut"  # std_msgs/Float64, per revolution [m]
BIT_HOLE_DEPTH = "~/bit/hole_depth"    # std_msgs/Float64 [m] below the start
TOP_DRIVE_WRENCH = "~/top_drive/wrench"  # WrenchStamped: torque.z surface torque, force.z hook load
JOINT_STATES = "~/joint_states"        # sensor_msgs/JointState
DIAGNOSTICS = "/diagnostics"           # diagnostic_msgs/DiagnosticArray, 1 Hz
CLOCK = "/clock"                       # rosgraph_msgs/Clock, with publish_clock

# services
SRV_RESET = "~/reset"                  # std_srvs/Trigger
SRV_PAUSE = "~/pause"                  # std_srvs/SetBool
SRV_STEP = "~/step"                    # std_srvs/Trigger

# frames ("bit": +z downhole at the bit; "top_drive": at the surface) and joint names live in
# bag.rig_messages, the frames accepted on commands in core.session
FRAME_TOP_DRIVE = rig_messages.FRAME_TOP_DRIVE


def qos(reliability: str, depth: int = 10) -> QoSProfile:
    """The QoS profile for the rig's topics: ``reliable`` (default) or ``best_effort``."""
    policy = {"reliable": ReliabilityPolicy.RELIABLE,
              "best_effort": ReliabilityPolicy.BEST_EFFORT}[reliability]
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=policy)
