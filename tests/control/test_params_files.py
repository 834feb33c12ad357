"""The controller's shipped params files (drill_sim/config/controller_*.yaml) hold what their
comments say: every key a parameter of ``drill_sim_controller`` and each law's gains its
reference tuning for ``base`` (``control.reference``), for the signals the file names."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from drill_sim.control import LAWS
from drill_sim.control.reference import reference_gains
from drill_sim.core import load_preset

CONFIG = Path(__file__).resolve().parents[2] / "drill_sim" / "config"
FILES = {"controller_off.yaml": None, "controller_stiff_pi.yaml": None,
         "controller_soft_speed.yaml": None, "controller_z_torque.yaml": None,
         "controller_z_torque_surface_rig.yaml": "surface_rig"}
NODE_KEYS = {"law", "rig", "sample_period_s", "impedance_nm_s_rad", "top_drive_inertia_kg_m2",
             "inputs", "manage_drive_mode", "enabled", "setpoint_topic",
             "initial_speed_setpoint_rad_s", "setpoint_lockstep", "diagnostics_period_s"}


def test_every_shipped_controller_file_is_listed():
    assert {p.name for p in CONFIG.glob("controller_*.yaml")} == set(FILES)


@pytest.mark.parametrize(("name", "profile"), FILES.items())
def test_params_file_holds_the_reference_tuning(name, profile):
    params = yaml.safe_load((CONFIG / name).read_text())["/**"]["ros__parameters"]
    law = params["law"]
    gains = {k.split(".", 1)[1]: v for k, v in params.items() if k.startswith(f"{law}.")}
    assert set(params) - {f"{law}.{g}" for g in gains} <= NODE_KEYS
    assert set(gains) <= set(LAWS[law].GAINS)
    expected = reference_gains(law, load_preset("base"),
                               params.get("top_drive_inertia_kg_m2", 2900.0),
                               sensor_profile=profile)
    for gain, value in expected.items():
        assert gains[gain] == pytest.approx(value, rel=1e-4), (name, gain)
