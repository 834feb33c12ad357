"""The vector environment (``gymnasium.make_vec("drill_sim/Rig-v0", num_envs=N)``): N rigs in
one compiled call a step, each equal to a ``RigEnv`` with its seed and actions. The reference is
independent of the vector path: gymnasium's own ``SyncVectorEnv`` of ``RigEnv`` (each rig
stepped by its session, sample by sample in Python), with the same seeds, auto-reset and
actions; observations, rewards, truncations, infos and the episodes' results agree to 1e-9."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest
from gymnasium.vector import SyncVectorEnv

import drill_sim.gym
from drill_sim.core import ParameterError
from drill_sim.gym import RigEnv
from drill_sim.gym.vector_env import RigVecEnv
from drill_sim.session.scenario import Scenario

# two short episodes of different lengths, drawn by each rig's seed: auto-resets at different
# steps; a set-point step and a weight-on-bit ramp inside the second
SHORT = [Scenario.of_points("short", ((0.0, 60.0),), ((0.0, 100.0),), duration_s=0.3,
                            window_start_s=0.1),
         Scenario.of_points("longer", ((0.0, 50.0), (0.2, 50.0), (0.3, 70.0)),
                            ((0.0, 120.0), (0.25, 120.0), (0.35, 140.0)), duration_s=0.5,
                            window_start_s=0.2)]


def _compare(mode: str, actions_of, steps: int = 130, n: int = 3, **more) -> int:
    kwargs = dict(preset="base", top_drive_mode=mode, scenarios=SHORT, control_period_s=0.01,
                  reward_weights={"torque_rate": 1.0}, **more)
    vec = gymnasium.make_vec(drill_sim.gym.ENV_ID, num_envs=n, **kwargs)
    assert isinstance(vec, RigVecEnv)
    ref = SyncVectorEnv([lambda: RigEnv(**kwargs) for _ in range(n)])
    obs_v, _ = vec.reset(seed=11)
    obs_r, _ = ref.reset(seed=11)
    assert np.allclose(obs_v, obs_r, rtol=1e-12, atol=0.0)
    ends = 0
    for step in range(steps):
        actions = actions_of(obs_r, step)
        out_v, out_r = vec.step(actions), ref.step(actions)
        for what, a, b in zip(("obs", "reward", "terminated", "truncated"), out_v[:4],
                              out_r[:4], strict=True):
            assert np.allclose(a, b, rtol=1e-9, atol=1e-9 * np.max(np.abs(b), initial=1.0)), \
                (step, what, a, b)
        info_v, info_r = out_v[4], out_r[4]
        for key in ("bit_speed_rad_s", "wob_n", "tob_nm", "time_s"):
            assert np.allclose(info_v[key], info_r[key], rtol=1e-9, atol=1e-6), (step, key)
        assert list(info_v["scenario"]) == list(info_r["scenario"])
        if "result" in info_r:
            ends += int(info_r["_result"].sum())
            assert list(info_v["_result"]) == list(info_r["_result"])
            for key in ("ssi", "stick_fraction", "mean_rop_m_h", "surface_torque_rms_nm",
                        "motor_torque_rms_nm", "drive_energy_j"):
                got, want = info_v["result"][key], info_r["result"][key]
                mask = info_r["_result"]
                assert np.allclose(got[mask], want[mask], rtol=1e-9, atol=1e-12), (step, key)
    vec.close()
    ref.close()
    return ends


@pytest.mark.parametrize("more", [
    {}, {"string_model": "distributed"}, {"sensor_profile": "surface_rig", "sensor_seed": 4},
    {"sensor_profile": "mud_pulse", "sensor_seed": 9}])
def test_each_rig_equals_a_rig_env_in_torque_mode(more):
    """Torque actions around the steady motor torque with a random wobble, and now and then
    one beyond the drive's limit (so the drive's rate limit, the rate penalty, weighted 1, and
    the clipping all act): every step of every rig as in the reference, over several
    auto-resets."""
    rng = np.random.default_rng(3)

    def actions(obs, step):
        out = obs[:, 1] + rng.normal(0.0, 4000.0, obs.shape[0])
        if step % 9 == 0:
            out[0] = 1e6                  # beyond the drive's limit: clipped, penalised
        return out[:, None]
    assert _compare("torque", actions, **more) >= 4


@pytest.mark.parametrize("more", [
    {}, {"string_model": "distributed"}, {"sensor_profile": "wired_pipe", "sensor_seed": 2}])
def test_each_rig_equals_a_rig_env_in_speed_mode(more):
    rng = np.random.default_rng(5)

    def actions(obs, step):
        return (obs[:, 4] + rng.normal(0.0, 0.5, obs.shape[0]))[:, None]
    assert _compare("speed", actions, **more) >= 4


def test_the_sensors_noise_continues_past_a_block(tmp_path):
    """4200 samples of a noisy 1 kHz motor torque in one episode (1 ms, 4.2 s): past the 4096
    deviates a channel's noise block holds, the rig's bank refills it as ``RigEnv``'s does."""
    from drill_sim.core.sensors import NOISE_BLOCK
    profile = tmp_path / "noisy.yaml"
    profile.write_text("description: noisy motor torque\nchannels:\n"
                       "  motor_torque_nm: {noise_std: 150.0}\n")
    steady = [Scenario.of_points("steady", ((0.0, 60.0),), ((0.0, 100.0),), duration_s=4.2,
                                 window_start_s=1.0)]
    kwargs = dict(preset="base", scenarios=steady, control_period_s=0.001,
                  sensor_profile=str(profile), sensor_seed=6)
    vec = RigVecEnv(2, **kwargs)
    ref = SyncVectorEnv([lambda: RigEnv(**kwargs) for _ in range(2)])
    vec.reset(seed=0)
    obs_r, _ = ref.reset(seed=0)
    for step in range(4200):
        obs_v, *_ = vec.step(obs_r[:, 1:2])
        obs_r, *_ = ref.step(obs_r[:, 1:2])
        if step > NOISE_BLOCK + 10 and step % 50 == 0:
            assert np.allclose(obs_v, obs_r, rtol=1e-9, atol=1e-9), step
    assert np.allclose(obs_v, obs_r, rtol=1e-9, atol=1e-9)


def test_a_different_action_or_seed_is_told_apart():
    """The comparison can fail: one rig given a slightly different torque, or the vector
    environment reset with another seed, no longer matches."""
    kwargs = dict(preset="base", scenarios=SHORT, control_period_s=0.01)
    vec = RigVecEnv(2, **kwargs)
    ref = SyncVectorEnv([lambda: RigEnv(**kwargs) for _ in range(2)])
    obs_v, _ = vec.reset(seed=1)
    obs_r, _ = ref.reset(seed=1)
    action = obs_r[:, 1:2].copy()
    nudged = action.copy()
    nudged[1] *= 1.0 + 1e-6
    for _ in range(5):
        obs_v, *_ = vec.step(nudged)
        obs_r, *_ = ref.step(action)
    assert np.allclose(obs_v[0], obs_r[0], rtol=1e-12)
    assert not np.allclose(obs_v[1], obs_r[1], rtol=1e-12, atol=0.0)
    other, _ = RigVecEnv(2, **kwargs).reset(seed=2)
    first, _ = RigVecEnv(2, **kwargs).reset(seed=1)
    assert np.array_equal(first, RigVecEnv(2, **kwargs).reset(seed=1)[0])
    assert not np.array_equal(first, other)


@pytest.mark.parametrize(("kwargs", "fragment"), [
    ({"num_envs": 0}, "num_envs = 0"),
    ({"num_envs": True}, "num_envs = True"),
    ({"string_model": "stiff"}, "string_model = 'stiff'"),
    ({"sensor_profile": "no_such_profile"}, "no_such_profile"),
    ({"sensor_seed": -1}, "sensor_seed = -1"),
    ({"perturbation": float("nan")}, "perturbation = nan"),
    ({"scenarios": "switch_on,standard", "top_drive_mode": "speed", "record": "x"}, "record"),
])
def test_what_the_compiled_path_does_not_run_is_refused_in_one_line(kwargs, fragment):
    args = {"num_envs": 2, "scenarios": SHORT} | kwargs
    with pytest.raises(ParameterError, match=fragment) as caught:
        RigVecEnv(**args)
    assert "\n" not in str(caught.value)


def test_bad_actions_are_refused_by_rig():
    vec = RigVecEnv(2, scenarios=SHORT)
    vec.reset(seed=0)
    with pytest.raises(ParameterError, match="rig 1"):
        vec.step(np.array([[0.0], [np.nan]]))
    for shape in ((2, 2), (4, 1), (3,)):
        with pytest.raises(ParameterError, match=r"expected \(2, 1\)"):
            vec.step(np.zeros(shape))
    for bad in (np.array([["a"], ["b"]]), [[object()], [1.0]], np.array([[1 + 1j], [0.0]]),
                np.array([[True], [False]])):
        with pytest.raises(ParameterError, match="expected real numbers"):
            vec.step(bad)
    obs, *_ = vec.step(np.zeros((2, 1)))             # and the rigs step on
    assert np.all(np.isfinite(obs))
