"""The effort figures (``core.effort``) wherever a run is scored, with the same names and
values: ``drill_sim control``'s rows and ``drill_sim bag metrics`` of the session the same
run recorded (the bag's motor torque, its drive limits and its recorded controller switch)."""

from __future__ import annotations

import json

import pytest

from drill_sim.cli.main import main
from drill_sim.core.effort import EFFORT_KEYS


def test_control_rows_and_the_recorded_bags_metrics_carry_the_same_effort(tmp_path, capsys):
    assert main(["control", "--scenarios", "switch_on", "--laws", "kinematic,z_torque",
                 "--json", "--record", str(tmp_path / "rec")]) == 0
    rows = {r["name"]: r for r in json.loads(capsys.readouterr().out)["rows"]}
    for row in rows.values():
        assert set(EFFORT_KEYS) <= set(row)
    kinematic, z = rows["kinematic"], rows["z_torque"]
    assert kinematic["time_at_torque_limit_fraction"] is None     # an ideal speed source
    assert kinematic["settling_time_s"] is None                   # the stick-slip goes on
    assert z["settling_time_s"] is not None and 0.0 < z["settling_time_s"] < 20.0
    assert z["time_at_torque_limit_fraction"] == 0.0
    # the window of switch_on starts at 35 s of 60
    assert main(["bag", "metrics", str(tmp_path / "rec" / "switch_on-z_torque"),
                 "--start", "35", "--json"]) == 0
    bag = json.loads(capsys.readouterr().out)
    for key in ("motor_torque_rms_nm", "motor_torque_p2p_nm", "torque_rate_rms_nm_s",
                "time_at_torque_limit_fraction", "drive_energy_j"):
        assert bag[key] == pytest.approx(z[key], rel=1e-9, abs=1e-12), key
    # the settling counts from the switch, which lies before that window: over the whole
    # bag; the node records a switch at the tick before the law's first sample
    assert bag["settling_time_s"] is None
    assert main(["bag", "metrics", str(tmp_path / "rec" / "switch_on-z_torque"),
                 "--json"]) == 0
    whole = json.loads(capsys.readouterr().out)
    assert whole["settling_time_s"] == pytest.approx(z["settling_time_s"], abs=2e-3)
