"""The offline closed loop runs the rig node's own session: its bag re-simulates exactly, its
commands pass the node's rules, and it starts as the node does (``initial_perturbation``)."""

from __future__ import annotations

import pytest

from drill_sim.bag.series import rig_series
from drill_sim.control.closed_loop import run_loop
from drill_sim.control.evaluation import LoopSettings, Scenario
from drill_sim.core import ParameterError, load_preset
from drill_sim.session.resim import resimulate


@pytest.fixture(scope="module")
def base():
    return load_preset("base")


def test_a_recorded_loop_resimulates_exactly_and_holds_what_the_loop_saw(base, tmp_path):
    """A WOB step with the law switched on, under noisy, late sensors: the bag re-runs bit for
    bit, and its samples are the loop's own series."""
    scenario = Scenario("step", ((0.0, 60.0),), ((0.0, 90.0), (1.0, 90.0), (1.5, 110.0)),
                        duration_s=3.0, window_start_s=1.0, switch_on_s=1.0)
    bag = tmp_path / "loop"
    r = run_loop(base, scenario, LoopSettings(law="z_torque", sensor_profile="surface_rig",
                                              sensor_seed=4), record=bag)
    result = resimulate(bag)
    assert result.exact, result.explanation()
    assert result.samples == 3001 and result.refused == 0
    assert result.max_difference["measured top_drive_speed_rad_s"] == 0.0
    recorded = rig_series(bag)
    assert (recorded.bit_speed_rad_s == r.series["bit_speed_rad_s"]).all()
    assert (recorded.wob_n == r.series["wob_n"]).all()


def test_the_loops_commands_pass_the_nodes_rules(base):
    """A set-point the rig node would refuse (above its largest top-drive speed) stops the
    loop with the node's refusal, as it would stop a lockstep run."""
    with pytest.raises(ParameterError, match="top-drive speed"):
        run_loop(base, Scenario("fast", ((0.0, 60.0), (0.5, 600.0)), ((0.0, 100.0),),
                                duration_s=1.0, window_start_s=0.5),
                 LoopSettings(law="kinematic"))
