"""Driller scenarios: set points, ramps, and bad files refused clearly."""

from __future__ import annotations

import pytest

from drill_sim.core import RPM, ParameterError
from drill_sim.session.scenario import load_scenario, scenario_from_dict, scenario_names


def test_shipped_scenarios():
    assert {"tag_bottom", "step_test"} <= set(scenario_names())
    tag = load_scenario("tag_bottom")
    assert tag.initial_state == "rest" and tag.duration_s == 60.0
    ws = 300e3
    assert tag.commands_at(0.0, ws) == (0.0, ws)                   # hanging, not rotating
    speed, hook = tag.commands_at(2.5, ws)
    assert speed == pytest.approx(30 * RPM) and hook == ws         # spinning up, still hanging
    assert tag.commands_at(16.0, ws)[1] == pytest.approx(ws - 100e3)
    assert tag.commands_at(59.0, ws)[0] == pytest.approx(200 * RPM)
    assert tag.controller is None
    on = load_scenario("controller_on")
    assert on.commands_at(59.0, ws)[0] == pytest.approx(60 * RPM)     # the controller clears it
    assert on.controller.law == "z_torque" and on.controller.on_at_s == 35.0
    step = load_scenario("step_test")
    assert step.commands_at(9.99, ws)[0] == pytest.approx(60 * RPM)
    assert step.commands_at(10.0, ws)[0] == pytest.approx(120 * RPM)


def test_hook_load_set_points_and_clamping():
    sc = scenario_from_dict("x", {"duration_s": 10, "points": [
        {"at_s": 0, "rpm": 10, "hook_load_kn": 50}, {"at_s": 5, "wob_kn": 400, "ramp": True}]})
    assert sc.commands_at(0, 300e3)[1] == 50e3
    assert sc.commands_at(5, 300e3)[1] == 0.0                      # never a negative hook load


@pytest.mark.parametrize("data, fragment", [
    ({"points": []}, "non-empty list"),
    ({"duration_s": 10, "points": [{"rpm": 3}]}, "at_s"),
    ({"duration_s": 10, "points": [{"at_s": 0, "rpm": -1, "wob_kn": 1}]}, "rpm"),
    ({"duration_s": 10, "points": [{"at_s": 1, "rpm": 1, "wob_kn": 1},
                                   {"at_s": 1, "rpm": 2}]}, "does not increase"),
    ({"duration_s": 10, "points": [{"at_s": 0, "rpm": 1, "torque": 1}]}, "expected a mapping"),
    ({"duration_s": 10, "points": [{"at_s": 0, "rpm": 1}]}, "one load"),
    ({"duration_s": 10, "points": [{"at_s": 0, "rpm": 1, "wob_kn": 1}],
      "controller": {"law": "pid", "on_at_s": 1}}, "law = 'pid'"),
    ({"duration_s": 10, "points": [{"at_s": 0, "rpm": 1, "wob_kn": 1}],
      "controller": {"law": "z_torque", "on_at_s": 11}}, "on_at_s"),
    ({"duration_s": 10, "points": [{"at_s": 0, "rpm": 1, "wob_kn": 1}],
      "controller": {"law": "z_torque"}}, "law and on_at_s"),
    ({"duration_s": 10, "initial_state": "upside", "points": [{"at_s": 0, "rpm": 1,
                                                                "wob_kn": 1}]}, "initial_state"),
])
def test_bad_scenarios_are_refused(data, fragment):
    with pytest.raises(ParameterError, match=fragment):
        scenario_from_dict("x", data)


def test_missing_and_corrupt_scenario_files(tmp_path):
    with pytest.raises(ParameterError, match="neither a shipped scenario"):
        load_scenario(tmp_path / "none.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("points: [\n")
    with pytest.raises(ParameterError, match="not valid YAML"):
        load_scenario(bad)
