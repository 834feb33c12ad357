"""``drill_sim tune`` end to end: a small study on two workers writes a params file, and the
installed ``drill_sim_controller`` starts from it with the tuned gains as its parameters."""

from __future__ import annotations

import subprocess

import yaml
from conftest import installed
from rcl_interfaces.srv import GetParameters
from rosutil import NodeProcess, call_service

SHORT = """description: "a short run for tests: 60 rpm, 100 kN, 6 s"
initial_state: steady
duration_s: 6.0
window_start_s: 3.0
points:
  - {at_s: 0.0, rpm: 60.0, wob_kn: 100.0}
"""


def test_tune_writes_a_params_file_the_controller_starts_from(ros, tmp_path):
    scenario = tmp_path / "short.yaml"
    scenario.write_text(SHORT)
    out = tmp_path / "tuned.yaml"
    proc = subprocess.run([installed("drill_sim"), "tune", "--law", "z_torque", "--params",
                           "kp_nm_s_rad,alpha", "--scenarios", str(scenario), "--trials", "4",
                           "--workers", "2", "--out", str(out)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "| reference | " in proc.stdout and "4 trials" in proc.stdout
    assert (tmp_path / "tuned.yaml.journal").is_file()
    params = yaml.safe_load(out.read_text())["/**"]["ros__parameters"]
    with NodeProcess("drill_sim_controller", "--ros-args", "--params-file", str(out),
                     "-r", "__ns:=/tuned"):
        got = call_service(ros, GetParameters, "/tuned/drill_sim_controller/get_parameters",
                           GetParameters.Request(names=["law", "z_torque.alpha",
                                                        "z_torque.kp_nm_s_rad"]))
    law, alpha, kp = got.values
    assert law.string_value == "z_torque"
    assert alpha.double_value == params["z_torque.alpha"]
    assert kp.double_value == params["z_torque.kp_nm_s_rad"]
    refused = subprocess.run([installed("drill_sim"), "tune", "--law", "z_torque", "--params",
                              "beta", "--out", str(out)], capture_output=True, text=True)
    assert refused.returncode == 2
    assert refused.stderr.strip() == ("drill_sim: error: z_torque has no gain 'beta' to tune: "
                                      "expected one of alpha, kp_nm_s_rad, ki_nm_rad, "
                                      "speed_lowpass_hz, torque_lowpass_hz, highpass_hz, "
                                      "measurement_period_s, torque_signal_tau_s, "
                                      "speed_signal_tau_s, alpha_min, backoff_per_s, "
                                      "saturation_target (the torque limits are the drive's)")
