"""``drill_sim control --ros``: the rig node and drill_sim_controller in lockstep, scored on the
rig's samples, give the offline loop's numbers (the same law, gains, sample instants and start)
to round-off; so a controller scored through the nodes is scored as the offline table is."""

from __future__ import annotations

import numpy as np
import pytest

from drill_sim.control.closed_loop import run_loop
from drill_sim.control.evaluation import LoopSettings, Scenario, sample_metrics
from drill_sim.control.reference import reference_gains
from drill_sim.core import load_preset
from drill_sim.ros.evaluation import run_ros


def test_ros_lockstep_scores_equal_the_offline_scores(ros):
    preset = load_preset("base")
    settings = LoopSettings(law="z_torque", gains=reference_gains("z_torque", preset, 2900.0),
                            perturbation=0.0)
    scenario = Scenario.of_points("step", ((0.0, 61.0),), ((0.0, 100.0),), duration_s=1.2,
                                  window_start_s=0.2, start_rpm=60.0)
    drive = preset.top_drive                                     # its limits: ±60 kN·m
    through_nodes = run_ros(preset, scenario, settings, timeout_s=300.0)
    offline = run_loop(preset, scenario, settings)
    assert np.allclose(through_nodes["time_s"], offline.series["time_s"], rtol=0, atol=1e-12)
    a = sample_metrics(preset, through_nodes, 0.2, drive, law="z_torque", scenario="step")
    b = sample_metrics(preset, offline.series, 0.2, drive, law="z_torque", scenario="step")
    assert b.surface_torque_p2p_nm > 0.5 and b.ssi > 1e-3        # a real transient
    for key in ("ssi", "mean_rop_m_h", "surface_torque_p2p_nm", "surface_torque_rms_nm",
                "mse_pa", "max_bit_speed_rpm"):
        assert getattr(a, key) == pytest.approx(getattr(b, key), rel=1e-9), key
    assert a.stick_fraction == b.stick_fraction


@pytest.mark.parametrize("law", ["z_torque", "kinematic"])
def test_ros_lockstep_plays_a_wob_step_and_a_speed_ramp_at_the_offline_instants(ros, law):
    """A set-point that changes reaches the rig (hook load, a lockstep topic) and the controller
    (stamped set-points it waits for) at the very samples the offline loop applies it: one tick
    early or late, or an order left to the wall clock, shows as a difference far above 1e-9."""
    preset = load_preset("base")
    gains = {} if law == "kinematic" else reference_gains(law, preset, 2900.0)
    settings = LoopSettings(law=law, gains=gains, perturbation=0.0)
    scenario = Scenario.of_points("step_ramp", ((0.0, 60.0), (0.2, 60.0), (1.0, 66.0)),
                                  ((0.0, 100.0), (0.6, 100.0), (0.7, 115.0)), duration_s=1.2,
                                  window_start_s=0.2)
    drive = None if law == "kinematic" else preset.top_drive
    through_nodes = run_ros(preset, scenario, settings, timeout_s=300.0)
    offline = run_loop(preset, scenario, settings)
    assert np.allclose(through_nodes["time_s"], offline.series["time_s"], rtol=0, atol=1e-12)
    for key in ("bit_speed_rad_s", "top_drive_speed_rad_s", "surface_torque_nm", "wob_n"):
        assert np.allclose(through_nodes[key], offline.series[key], rtol=1e-9, atol=1e-9), key
    a = sample_metrics(preset, through_nodes, 0.2, drive, law=law, scenario="step_ramp")
    b = sample_metrics(preset, offline.series, 0.2, drive, law=law, scenario="step_ramp")
    wob = offline.series["wob_n"]
    assert wob[-1] - wob[0] > 5e3                                # the step reached the bit
    for key in ("ssi", "mean_rop_m_h", "surface_torque_p2p_nm", "surface_torque_rms_nm",
                "mse_pa", "mean_bit_speed_rpm", "max_bit_speed_rpm"):
        assert getattr(a, key) == pytest.approx(getattr(b, key), rel=1e-9), key
    assert a.stick_fraction == b.stick_fraction


def test_ros_lockstep_switches_the_law_on_at_the_offline_sample(ros):
    """A switch-on: the controller runs the drive's stiff loop, then the law takes over at
    sample ceil(switch_on_s / h), as offline; a switch a tick early or late (or at whatever
    sample the parameter happened to arrive) shows in the series far above round-off."""
    preset = load_preset("base")
    settings = LoopSettings(law="z_torque", gains=reference_gains("z_torque", preset, 2900.0),
                            perturbation=0.0)
    scenario = Scenario.of_points("switch", ((0.0, 60.0),), ((0.0, 100.0),), duration_s=1.0,
                                  window_start_s=0.2, switch_on_s=0.4, start_rpm=61.0)
    through_nodes = run_ros(preset, scenario, settings, timeout_s=300.0)
    offline = run_loop(preset, scenario, settings)
    stiff = run_loop(preset, Scenario.of_points("stiff", ((0.0, 60.0),), ((0.0, 100.0),),
                                                duration_s=1.0, window_start_s=0.2,
                                                switch_on_s=1.0, start_rpm=61.0), settings)
    late = slice(450, None)                              # the switch made a difference
    assert not np.allclose(stiff.series["motor_torque_nm"][late],
                           offline.series["motor_torque_nm"][late], rtol=1e-6, atol=0)
    for key in ("bit_speed_rad_s", "top_drive_speed_rad_s", "surface_torque_nm",
                "motor_torque_nm"):
        assert np.allclose(through_nodes[key], offline.series[key], rtol=1e-9, atol=1e-9), key
