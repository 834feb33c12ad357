"""A policy as a law (``control.policy``): loaded by name with clear refusals, fed the
environment's observation, and holding its last command when the policy misbehaves."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drill_sim.control.laws import SurfaceMeasurement
from drill_sim.control.policy import OBSERVATION, PolicyLaw, load_policy
from drill_sim.control.supervisor import Supervisor
from drill_sim.core import ParameterError


@pytest.mark.parametrize(("spec", "words"), [
    ("no_colon", "expected package.module:callable"),
    ("not_a_module_xyz:f", "cannot import not_a_module_xyz"),
    ("drill_sim.control.policy:missing", "has no missing"),
    ("drill_sim.control.policy:OBSERVATION", "is not callable"),
])
def test_a_bad_policy_name_says_what_is_wrong(spec, words):
    with pytest.raises(ParameterError, match=words):
        load_policy(spec)


def test_the_policy_sees_the_environments_observation_and_its_action_is_the_torque():
    seen = []

    def policy(obs):
        seen.append(obs)
        return np.array([1234.5])

    law = PolicyLaw(1e-3, 300.0, 2900.0, policy)
    law.set_speed(6.4)
    law.hook_load_n = 5e5
    out = law.step(SurfaceMeasurement(0.0, 6.3, 5000.0, 4900.0))
    assert out == 1234.5
    assert dict(zip(OBSERVATION, seen[0], strict=True)) == {
        "top_drive_speed_rad_s": 6.3, "motor_torque_nm": 5000.0, "surface_torque_nm": 4900.0,
        "hook_load_n": 5e5, "speed_setpoint_rad_s": 6.4}


@pytest.mark.parametrize("bad", [lambda o: np.array([math.nan]), lambda o: [1.0, 2.0],
                                 lambda o: 1 / 0])
def test_a_misbehaving_policy_holds_the_last_command_and_is_counted(bad):
    calls = {"n": 0}

    def policy(obs):
        calls["n"] += 1
        return 100.0 if calls["n"] == 1 else bad(obs)

    law = PolicyLaw(1e-3, 300.0, 2900.0, policy)
    m = SurfaceMeasurement(0.0, 6.3, 5000.0, 4900.0)
    assert law.step(m) == 100.0
    assert law.step(m) == 100.0 and law.refused == 1 and law.last_problem


def test_the_supervisor_runs_law_policy_only_with_a_policy():
    with pytest.raises(ParameterError, match="needs a policy"):
        Supervisor(1e-3, 300.0, 2900.0, "policy", {})
    sup = Supervisor(1e-3, 300.0, 2900.0, "policy", {}, policy=lambda o: 7.0)
    assert sup.step(SurfaceMeasurement(0.0, 6.3, 5000.0, 4900.0)) == 7.0
