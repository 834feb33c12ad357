"""What a rig shows at one instant (``RigSample``, SI), the bit's regimes by name, and the rpm
unit: the values the node publishes, the recorder keeps and every tool reads."""

from __future__ import annotations

import math
from typing import NamedTuple

from . import kernel as kn

RPM = 2.0 * math.pi / 60.0   # rad/s per rpm

# The bit's regime in the last step, as the kernel decides it (model contract, 2.2); published
# by the node and recorded, so every consumer uses the kernel's own decision.
REGIME_ROTATING, REGIME_STUCK, REGIME_OFF_BOTTOM = (kn.REGIME_ROTATING, kn.REGIME_STUCK,
                                                   kn.REGIME_OFF_BOTTOM)
REGIME_NAMES = {REGIME_ROTATING: "rotating", REGIME_STUCK: "stuck",
                REGIME_OFF_BOTTOM: "off_bottom"}


class RigSample(NamedTuple):
    """What a rig shows at one instant, SI. Axial quantities are positive downhole.

    A named tuple rather than a dataclass: the node builds one every tick, and this is 10x
    cheaper to construct."""

    time_s: float
    bit_speed_rad_s: float
    rop_m_s: float                 # bit axial velocity (rate of penetration when > 0)
    wob_n: float                   # weight on bit, mean since the previous sample (stick reaction
    tob_nm: float                  # included); torque on bit, likewise (see Rig.sample)
    surface_torque_nm: float       # string torque C (phi_td - phi), as the top drive measures it
    depth_of_cut_m: float          # per revolution, d = n d_n (negative off bottom)
    bit_depth_m: float             # bit position below its start
    hole_depth_m: float            # deepest point of the hole below the bit's start
    bit_angle_rad: float
    top_drive_angle_rad: float
    top_drive_speed_rad_s: float   # the top drive's (kinematic mode: the command)
    hook_load_n: float             # commanded; measured with the hook in position mode
    stuck: bool
    off_bottom: bool
    stick_slip: bool               # a stick phase within the stick-slip window
    regime: int                    # the kernel's regime of the last step: REGIME_* below
    top_drive_speed_setpoint_rad_s: float  # the speed command (unused in torque mode)
    motor_torque_nm: float         # applied, after limits and lag (kinematic mode: the string
                                   # torque, the torque that holds the commanded speed)
