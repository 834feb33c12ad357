"""``drill_sim_drive hold``: one line to hold a top-drive speed and a weight on bit."""

from __future__ import annotations

import subprocess

import pytest
from conftest import installed
from rosutil import NodeProcess, wait_for
from sensor_msgs.msg import JointState

from drill_sim.core import RPM


def test_hold_puts_the_speed_and_weight_on_the_rig(ros, base):
    ws = base.rig.submerged_weight_n
    joints: list[JointState] = []
    with NodeProcess("drill_sim_node", "--ros-args", "-r", "__ns:=/hold"), \
            NodeProcess("drill_sim_drive", "hold", "--rpm", "90", "--wob-kn", "80",
                        "--ros-args", "-r", "__ns:=/hold") as drive:
        ros.create_subscription(JointState, "/hold/drill_sim/joint_states", joints.append, 100)

        def held() -> bool:
            return bool(joints) and joints[-1].velocity[0] == pytest.approx(90 * RPM) \
                and joints[-1].effort[1] == pytest.approx(ws - 80e3)
        wait_for(held, ros, 30.0, "the rig at 90 rpm and 80 kN on bit")
        assert drive.proc.poll() is None                   # holds until stopped
        code, out = drive.stop()
    assert code == 0 and "Traceback" not in out
    assert "hold 90 rpm, 80 kN on bit" in out


@pytest.mark.parametrize("args, fragment", [
    (["hold"], "hold needs --rpm and one of --wob-kn or --hook-load-kn"),
    (["hold", "--rpm", "60"], "hold needs --rpm"),
    (["hold", "--rpm", "-1", "--wob-kn", "100"], "rpm = -1.0 is out of range"),
    (["step_test", "--rpm", "60"], "--rpm: only with the hold scenario"),
])
def test_hold_bad_arguments_are_one_line(args, fragment):
    proc = subprocess.run([installed("drill_sim_drive"), *args], capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 2
    assert fragment in proc.stderr.strip().splitlines()[-1], proc.stderr
