"""The Gymnasium environment (``drill_sim.gym``): Gymnasium's own checker, a reference law run
as a policy through it scores as ``drill_sim control`` scores the law (the same session, the
same samples), a recorded episode is a bag ``bag resim`` re-runs exactly, and bad parameters are
refused by name."""

from __future__ import annotations

import math

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import drill_sim.gym
from drill_sim.control.closed_loop import run_loop
from drill_sim.control.evaluation import LoopSettings
from drill_sim.control.reference import reference_gains
from drill_sim.core import ParameterError, load_preset
from drill_sim.gym import ReferencePolicy, RigEnv
from drill_sim.session.resim import resimulate
from drill_sim.session.scenario import Scenario

STEADY = Scenario.steady(60.0, 100.0, duration_s=20.0, window_start_s=10.0)
# a set-point step (60 -> 70 rpm over 8-9 s) inside the episode: the policy must see it on time
STEP = Scenario.of_points("step", ((0.0, 60.0), (8.0, 60.0), (9.0, 70.0)), ((0.0, 100.0),),
                          duration_s=20.0, window_start_s=10.0)


def _episode(env: RigEnv, policy=None, seed: int = 0, options=None):
    """Run one episode; (rewards, last info)."""
    obs, info = env.reset(seed=seed, options=options)
    if policy is not None:
        policy.reset(env)
    rewards = []
    while True:
        action = policy(obs) if policy is not None else np.array([env.held_action])
        obs, reward, terminated, truncated, info = env.step(action)
        rewards.append(reward)
        assert env.observation_space.contains(obs) and not terminated
        if truncated:
            return rewards, info


def test_gymnasiums_checker_passes_and_make_builds_it():
    env = gymnasium.make(drill_sim.gym.ENV_ID, preset="base", scenarios="grid")
    assert isinstance(env.unwrapped, RigEnv)
    check_env(env.unwrapped, skip_render_check=True)
    check_env(RigEnv("base", top_drive_mode="speed"), skip_render_check=True)


@pytest.mark.parametrize(("profile", "seed"), [("ideal", 0), ("surface_rig", 7)])
def test_z_torque_as_a_policy_scores_as_drill_sim_control(profile, seed):
    """The same SSI, stick fraction and ROP (1e-9) as the offline loop with the same law,
    gains, scenario, sensors and seed; a different sensor seed or policy moves them."""
    preset = load_preset("base")
    gains = reference_gains("z_torque", preset, 2900.0, sensor_profile=profile,
                            sample_period_s=0.01)
    offline = run_loop(preset, STEP, LoopSettings(
        law="z_torque", gains=gains, sample_period_s=0.01, sensor_profile=profile,
        sensor_seed=seed))
    env = RigEnv("base", scenarios=[STEP], sensor_profile=profile, sensor_seed=seed)
    _, info = _episode(env, ReferencePolicy(env, "z_torque", gains))
    result = info["result"]
    for name in ("ssi", "stick_fraction", "mean_rop_m_h"):
        assert result[name] == pytest.approx(getattr(offline, name), rel=1e-9, abs=1e-12), name
    assert offline.ssi > 0.05                            # a run with something to score
    stiff = RigEnv("base", scenarios=[STEP], sensor_profile=profile, sensor_seed=seed)
    _, other = _episode(stiff, ReferencePolicy(stiff, "stiff_pi"))
    assert other["result"]["ssi"] != pytest.approx(result["ssi"], rel=1e-3)
    if profile != "ideal":
        reseeded = RigEnv("base", scenarios=[STEP], sensor_profile=profile,
                          sensor_seed=seed + 1)
        _, moved = _episode(reseeded, ReferencePolicy(reseeded, "z_torque", gains))
        assert moved["result"]["ssi"] != result["ssi"]


def test_reset_with_a_seed_is_reproducible_and_draws_the_scenario():
    env = RigEnv("base", scenarios="grid", control_period_s=0.05)
    drawn = {env.reset(seed=s)[1]["scenario"] for s in range(12)}
    assert len(drawn) > 3                                # the seed draws among the nine
    first, info = env.reset(seed=5)
    again, info_again = env.reset(seed=5)
    assert info["scenario"] == info_again["scenario"] and np.array_equal(first, again)
    a = [env.step(np.array([5e3]))[1] for _ in range(50)]
    env.reset(seed=5)
    assert a == [env.step(np.array([5e3]))[1] for _ in range(50)]


def test_the_reward_and_the_observation_are_in_si():
    """Held at the steady torque, the rig stays on its steady state: the observation is the
    surface sensors' (speed, motor and surface torque, hook load) and the set-point; the bit
    on its set-point earns ~0; the reward adds the weights' penalties."""
    fast = Scenario.steady(150.0, 90.0, duration_s=2.0, window_start_s=1.0)
    env = RigEnv("base", scenarios=[fast], control_period_s=0.01)
    obs, info = env.reset(seed=0)
    speed = 150 * 2 * math.pi / 60
    assert obs[0] == pytest.approx(speed) and obs[4] == pytest.approx(speed)
    assert obs[3] == pytest.approx(load_preset("base").rig.submerged_weight_n - 90e3)
    assert obs[1] == pytest.approx(info["tob_nm"]) == pytest.approx(obs[2])
    _, reward, _, _, _ = env.step(np.array([env.held_action]))
    assert -1e-3 < reward <= 0.0
    _, reward, _, _, _ = env.step(np.array([1e9]))              # held at the drive's limit
    assert reward <= -0.1


def test_the_reward_is_each_weights_penalty_by_hand():
    """Every term of the reward by hand (gym.md): the speed's squared relative error, the
    stick, the action on a limit, the rate of the held torque over the period in MN m/s,
    squared; an action past the limit is paid as the drive holds it (the limit), not as given."""
    fast = Scenario.steady(150.0, 90.0, duration_s=2.0, window_start_s=1.0)
    weights = {"speed": 0.5, "stick": 2.0, "saturation": 0.3, "torque_rate": 0.7}
    env = RigEnv("base", scenarios=[fast], control_period_s=0.01, reward_weights=weights)
    env.reset(seed=0)
    target = 150 * 2 * math.pi / 60
    high = load_preset("base").top_drive.motor_torque_max_nm
    for action in (env.held_action + 8e3, 1e9):
        before = env.held_action
        held = min(action, high)
        _, reward, _, _, info = env.step(np.array([action]))
        rate_mn_m_s = abs(held - before) / 0.01 / 1e6
        expected = -(0.5 * ((info["bit_speed_rad_s"] - target) / target) ** 2
                     + 2.0 * float(info["stuck"]) + 0.3 * float(held == high)
                     + 0.7 * rate_mn_m_s ** 2)
        assert reward == pytest.approx(expected, rel=1e-12)
        assert env.held_action == held


def test_a_recorded_episode_resimulates_exactly(tmp_path):
    short = Scenario.steady(60.0, 100.0, duration_s=3.0, window_start_s=1.0)
    env = RigEnv("base", scenarios=[short], record=tmp_path)
    _episode(env, ReferencePolicy(env, "z_torque"))
    result = resimulate(tmp_path / "episode_0")
    assert result.exact, result.explanation()


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"top_drive_mode": "position"}, "top_drive_mode = 'position'"),
    ({"control_period_s": 0.5}, "control_period_s = 0.5"),
    ({"control_period_s": 5e-5}, r"expected a finite number >= 0.0001 and <= 0.1"),
    ({"scenarios": "bogus"}, "scenario set 'bogus' is unknown"),
    ({"reward_weights": {"ssi": 1.0}}, "reward weight 'ssi' is unknown"),
    ({"reward_weights": {"stick": -1.0}}, "reward weight stick = -1.0"),
    ({"preset": "nowhere"}, "nowhere"),
])
def test_bad_parameters_are_refused_by_name(kwargs, words):
    with pytest.raises((ParameterError, FileNotFoundError, ValueError), match=words):
        RigEnv(**kwargs)


@pytest.mark.parametrize("action", ["abc", object(), 1 + 2j, True, np.array([True]),
                                    [[1.0], [2.0, 3.0]]])
def test_an_action_that_is_not_a_real_number_is_refused_by_name(action):
    env = RigEnv("base", scenarios=[STEADY])
    env.reset(seed=0)
    with pytest.raises(ParameterError, match=r"action .*: expected real numbers"):
        env.step(action)
    obs, *_ = env.step(np.array([env.held_action]))      # the episode goes on
    assert np.all(np.isfinite(obs))


def test_a_preset_that_is_not_a_name_or_a_path_is_refused():
    with pytest.raises(ParameterError, match="preset = True: expected a shipped preset's name"):
        RigEnv(preset=True)


def test_a_step_after_the_episode_ended_asks_for_a_reset():
    short = Scenario.steady(60.0, 100.0, duration_s=0.03, window_start_s=0.0)
    env = RigEnv("base", scenarios=[short])
    env.reset(seed=0)
    truncated = False
    while not truncated:
        *_, truncated, _ = env.step(np.array([env.held_action]))
    with pytest.raises(RuntimeError, match=r"step after the episode ended .* call reset\(\)"):
        env.step(np.array([env.held_action]))
    env.reset(seed=0)
    env.step(np.array([env.held_action]))


def test_a_bad_action_is_refused_and_the_episode_goes_on():
    env = RigEnv("base", scenarios=[STEADY])
    env.reset(seed=0)
    with pytest.raises(ParameterError, match="action nan: expected a finite motor torque"):
        env.step(np.array([math.nan]))
    with pytest.raises(ParameterError, match="action of 2 values: expected one"):
        env.step(np.array([1.0, 2.0]))
    obs, *_ = env.step(np.array([env.held_action]))
    assert np.all(np.isfinite(obs))
    with pytest.raises(RuntimeError, match="reset"):
        RigEnv("base").step(np.array([0.0]))
    with pytest.raises(ParameterError, match="options scenario = 9: expected 0 to 0"):
        env.reset(seed=0, options={"scenario": 9})
