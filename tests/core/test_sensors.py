"""The sensor model against its definition, computed independently here: noise statistics,
exact delays, zero-order hold, quantisation, the filter's analytic step response, seeding."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from drill_sim.core.parameters import ParameterError
from drill_sim.core.sensor_profile import (
    CHANNELS,
    SensorProfile,
    load_profile,
    profile_from_dict,
    profile_names,
)
from drill_sim.core.sensors import NOISE_BLOCK, SEVERITY_MAX, SensorBank

EXACT = dict(surface_torque_nm=5.0e3, top_drive_speed_rad_s=6.0, motor_torque_nm=5.5e3,
             hook_load_n=1.0e6, wob_n=1.0e5, tob_nm=3.0e3, bit_speed_rad_s=6.0)


def bank(channel: str, dt_s: float = 1e-3, seed: int = 0, **spec) -> SensorBank:
    """A bank whose ``channel`` has the sensor ``spec``; the others exact."""
    return SensorBank(profile_from_dict("test", {"channels": {channel: spec}}), dt_s, seed)


def sample(**values: float) -> SimpleNamespace:
    return SimpleNamespace(**{**EXACT, **values})


def run(b: SensorBank, channel: str, times, values) -> tuple[np.ndarray, np.ndarray]:
    """(measured, fresh) of ``channel`` at each time, its exact value given."""
    i = CHANNELS.index(channel)
    out, fresh = [], []
    for t, v in zip(times, values, strict=True):
        m = b.measure(t, sample(**{channel: v}))
        out.append(m[1 + i])
        fresh.append(m.fresh[i])
    return np.array(out), np.array(fresh)


def test_noise_mean_and_std_match_the_profile():
    """Over n samples the mean is value + bias within 5 sigma/sqrt(n) and the standard
    deviation noise_std within 5 sigma/sqrt(2n); sigma = 2 so a variance (4) or a
    half-scaled noise (1) is far outside."""
    n, sigma, bias = 200_000, 2.0, 0.5
    b = bank("hook_load_n", noise_std=sigma, bias=bias)
    out, fresh = run(b, "hook_load_n", np.arange(n) * 1e-3, np.full(n, 10.0))
    assert fresh[1:].all()
    assert abs(out.mean() - 10.5) < 5 * sigma / math.sqrt(n)
    assert abs(out.std() - sigma) < 5 * sigma / math.sqrt(2 * n)
    # white: neighbouring samples uncorrelated within sampling error
    r = np.corrcoef(out[1:], out[:-1])[0, 1]
    assert abs(r) < 5 / math.sqrt(n)


def test_delay_is_exact_in_samples_and_the_value_is_held():
    """100 Hz, 30 ms late, calls every ms of a ramp x = t: at each call the value shown is the
    ramp at the last sample instant at least 30 ms back, fresh exactly at each instant."""
    dt, period, delay = 1e-3, 0.01, 0.03
    b = bank("wob_n", rate_hz=1 / period, delay_s=delay)
    k = np.arange(2000)
    times = k * dt
    out, fresh = run(b, "wob_n", times, times * 1e5)
    shown_k = (k - 30) // 10 * 10                 # call index of the sample shown
    expected = np.where(k >= 30, np.maximum(shown_k, 0) * dt * 1e5, 0.0)
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-6)
    assert (fresh == ((k >= 30) & (k % 10 == 0))).all()


def test_zero_order_hold_between_samples_at_a_rate_the_ticks_do_not_divide():
    """7 Hz sampled by 1 kHz ticks: each instant j/7 s is taken at the first tick at or after
    it and held until the next."""
    b = bank("tob_nm", rate_hz=7.0)
    k = np.arange(3000)
    times = k * 1e-3
    values = np.sin(times * 5.0) * 1e3
    out, fresh = run(b, "tob_nm", times, values)
    taken = np.ceil(np.arange(0, 22) / 7.0 / 1e-3 - 1e-9).astype(int)   # tick of each instant
    taken = taken[taken < len(k)]
    assert (np.flatnonzero(fresh) == taken).all()
    last = taken[np.searchsorted(taken, k, side="right") - 1]
    np.testing.assert_array_equal(out, values[last])


def test_quantisation_rounds_to_the_nearest_step():
    q = 0.25
    b = bank("surface_torque_nm", quantum=q)
    values = np.random.default_rng(1).uniform(-100, 100, 10_000)
    out, _ = run(b, "surface_torque_nm", np.arange(len(values)) * 1e-3, values)
    steps = out / q
    np.testing.assert_array_equal(steps, np.round(steps))
    assert np.abs(out - values).max() <= q / 2 + 1e-12
    assert len(np.unique(out)) > 700                      # it is a step of q, not a coarser one


@pytest.mark.parametrize("quantum", [1e-15, 1e-9, 1e3, 1e9])
def test_quantisation_at_the_ends_of_its_range_never_overflows(quantum):
    """Any accepted quantum, however small or large against the value: the nearest multiple,
    in floating point (a quantum of 1e-15 on a WOB of 99.9 kN showed -9223.37 N: x/q cast to an
    int64 overflowed)."""
    b = bank("wob_n", quantum=quantum)
    values = np.array([99_939.0, -250e3, 0.0, 1.5e5, 1e9 - 1.0])
    out, _ = run(b, "wob_n", np.arange(len(values)) * 1e-3, values)
    np.testing.assert_allclose(out, np.round(values / quantum) * quantum, rtol=1e-15, atol=0)
    # within half a step, or the value's own floating-point resolution where that is coarser
    bound = quantum / 2 * (1 + 1e-12) + 4 * np.abs(np.spacing(values))
    assert np.all(np.abs(out - values) <= bound)


@pytest.mark.parametrize("irregular", [False, True])
def test_first_order_filter_step_response_is_the_analytic_exponential(irregular):
    """A unit step seen at t1 and held: y(t) = 1 - exp(-(t - t1)/tau) at every later call,
    for regular and irregular call intervals (the discretisation is exact)."""
    tau = 0.05
    gaps = np.random.default_rng(2).uniform(2e-4, 3e-3, 400) if irregular else np.full(400, 1e-3)
    times = np.concatenate([[0.0], np.cumsum(gaps)])
    values = np.where(np.arange(len(times)) >= 1, 1.0, 0.0)
    b = bank("hook_load_n", filter_tau_s=tau)
    out, _ = run(b, "hook_load_n", times, values)
    t1 = times[1]
    expected = np.where(times >= t1, 1.0 - np.exp(-(times - t1) / tau), 0.0)
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-12)


def test_same_seed_same_measurements_different_seed_different_and_reset_repeats():
    def series(seed: int, b: SensorBank | None = None) -> np.ndarray:
        b = b or SensorBank("mud_pulse", 1e-3, seed)
        rng = np.random.default_rng(0)
        rows = []
        for k in range(3000):       # more than a noise block: the refill is repeated too
            s = sample(**{c: EXACT[c] * (1 + 0.1 * rng.standard_normal()) for c in EXACT})
            rows.append(b.measure(k * 1e-3, s)[1:9])
        return np.array(rows)

    a = series(7)
    np.testing.assert_array_equal(a, series(7))
    assert not np.array_equal(a, series(8))
    b = SensorBank("mud_pulse", 1e-3, 7)
    series(7, b)
    b.reset()
    np.testing.assert_array_equal(a, series(7, b))


def test_noise_blocks_refill_without_repeating():
    """Past NOISE_BLOCK samples the deviates continue the generator's stream."""
    b = bank("hook_load_n", noise_std=1.0)
    n = 2 * NOISE_BLOCK + 10
    out, _ = run(b, "hook_load_n", np.arange(n) * 1e-3, np.zeros(n))
    rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence(0).spawn(len(CHANNELS))[
        CHANNELS.index("hook_load_n")]))
    np.testing.assert_array_equal(out, rng.standard_normal(n))


def test_a_channels_noise_does_not_depend_on_another_channels_rate():
    def hook(profile: dict) -> np.ndarray:
        b = SensorBank(profile_from_dict("t", {"channels": profile}), 1e-3, 5)
        return np.array([b.measure(k * 1e-3, sample()).hook_load_n for k in range(500)])

    noisy = {"hook_load_n": {"noise_std": 1.0}}
    np.testing.assert_array_equal(
        hook(noisy), hook({**noisy, "wob_n": {"noise_std": 3.0, "rate_hz": 13.0}}))


def test_stick_slip_severity_is_the_ssi_of_each_window():
    """Bit speed w0 + A sin(2 pi f t) over whole periods: (max - min)/(2 mean) = A / w0;
    a bit stopped for a whole window shows SEVERITY_MAX; nothing before the first window."""
    w0, amp, window = 6.0, 3.0, 2.0
    b = bank("stick_slip_severity", window_s=window)
    times = np.arange(6000) * 1e-3
    speeds = w0 + amp * np.sin(2 * np.pi * 2.0 * times + 0.3)
    shown = np.array([b.measure(t, sample(bit_speed_rad_s=v)).stick_slip_severity
                      for t, v in zip(times, speeds, strict=True)])
    assert (shown[times < window] == 0.0).all()
    assert np.abs(shown[times >= window] - amp / w0).max() < 1e-4
    stopped = [b.measure(6.0 + k * 1e-3, sample(bit_speed_rad_s=0.0)).stick_slip_severity
               for k in range(2001)]
    assert stopped[-1] == SEVERITY_MAX


def test_stick_slip_severity_divides_by_the_mean_not_the_mid_range():
    """A stick-slip-like bit speed (stuck 40 % of each 0.5 s period, then a half-sine burst to
    P): over whole periods (max - min)/(2 mean) = pi/2.4 = 1.309, where the mid-range would
    give 1 and a sine cannot tell the two apart. Expected from the samples themselves."""
    window, peak = 2.0, 20.0
    b = bank("stick_slip_severity", window_s=window)
    times = np.arange(6000) * 1e-3
    phase = (np.arange(6000) % 500) / 500.0
    speeds = np.where(phase < 0.4, 0.0, peak * np.sin(np.pi * (phase - 0.4) / 0.6))
    shown = np.array([b.measure(t, sample(bit_speed_rad_s=v)).stick_slip_severity
                      for t, v in zip(times, speeds, strict=True)])
    block = speeds[:2000]                               # four whole periods
    expected = (block.max() - block.min()) / (2.0 * block.mean())
    assert expected == pytest.approx(np.pi / 2.4, rel=2e-3)
    assert np.abs(shown[times >= window] - expected).max() < 1e-3 * expected


def test_ideal_profile_is_the_exact_value_every_tick():
    b = SensorBank("ideal", 1e-3)
    rng = np.random.default_rng(3)
    for k in range(100):
        s = sample(**{c: float(rng.normal()) * EXACT[c] for c in EXACT})
        m = b.measure(k * 1e-3, s)
        assert all(getattr(m, c) == getattr(s, c) for c in EXACT)
        assert all(m.fresh)


def test_the_kernel_allocates_nothing_inside():
    """Heap allocations per call are the call boundary's alone: the same whether a call
    only copies (ideal) or samples, draws noise and runs the delay ring (a noisy profile)."""
    from numba.core.runtime import rtsys

    def allocations(profile: str | SensorProfile) -> int:
        b = SensorBank(profile, 1e-3, 1)
        b.measure(0.0, sample())
        before = rtsys.get_allocation_stats().alloc
        for k in range(1, 1000):
            b.measure(k * 1e-3, sample())
        return rtsys.get_allocation_stats().alloc - before

    noisy = {c: {"rate_hz": 500.0, "delay_s": 0.05, "noise_std": 1.0, "quantum": 0.1,
                 "filter_tau_s": 0.01} for c in CHANNELS}
    assert allocations("ideal") == allocations(profile_from_dict("noisy", {"channels": noisy}))


def test_shipped_profiles_load():
    assert {"ideal", "surface_rig", "mud_pulse", "wired_pipe"} <= set(profile_names())
    for name in profile_names():
        p = load_profile(name)
        assert set(p.channels) == set(CHANNELS) and p.description
    assert load_profile("mud_pulse").channels["wob_n"].delay_s >= 10.0


@pytest.mark.parametrize("data, words", [
    ({"channels": {"wob_n": {"delay": 1.0}}}, ["wob_n", "unknown key", "'delay'", "delay_s"]),
    ({"channels": {"wob_n": {"delay_s": -1.0}}}, ["wob_n", "delay_s = -1.0", "non-negative"]),
    ({"channels": {"wob_n": {"noise_std": float("nan")}}}, ["noise_std", "finite"]),
    ({"channels": {"wob_n": {"rate_hz": 0}}}, ["rate_hz = 0", "positive"]),
    ({"channels": {"wob_n": {"quantum": "fine"}}}, ["quantum = 'fine'", "finite number"]),
    ({"channels": {"wob_n": {"window_s": 3.0}}}, ["window_s", "stick_slip_severity"]),
    ({"channels": {"torque": {}}}, ["unknown channel", "'torque'", "surface_torque_nm"]),
    ({"channel": {}}, ["unknown key", "'channel'", "channels"]),
    ({"channels": [1, 2]}, ["channels must be a mapping"]),
    ([1], ["expected a mapping"]),
    ({"channels": {"wob_n": {"rate_hz": 1e3, "delay_s": 1e5}}}, ["buffer more than"]),
])
def test_bad_profiles_are_refused_with_what_was_expected(data, words):
    with pytest.raises(ParameterError) as err:
        profile_from_dict("mine", data)
    assert "sensor profile 'mine'" in str(err.value)
    for w in words:
        assert w in str(err.value)


def test_a_negative_bias_is_allowed_and_a_missing_profile_named():
    assert profile_from_dict("b", {"channels": {"wob_n": {"bias": -2.0}}}).channels[
        "wob_n"].bias == -2.0
    with pytest.raises(ParameterError, match="neither a shipped sensor profile"):
        load_profile("no_such_profile")
    with pytest.raises(ParameterError, match="seed"):
        SensorBank("ideal", 1e-3, -1)
    with pytest.raises(ParameterError, match="dt_s"):
        SensorBank("ideal", float("nan"))


def test_a_series_measured_offline_equals_the_calls_one_by_one():
    """measure_series (compiled rows) and measure (one call a tick) give the same bits, across
    noise refills."""
    n = 3 * NOISE_BLOCK
    times = np.arange(n) * 1e-3
    rng = np.random.default_rng(4)
    columns = {c: EXACT[c] * (1 + 0.1 * rng.standard_normal(n)) for c in EXACT}
    series = SensorBank("wired_pipe", 1e-3, 9).measure_series(times, columns)
    b = SensorBank("wired_pipe", 1e-3, 9)
    for k in range(n):
        m = b.measure(times[k], sample(**{c: columns[c][k] for c in EXACT}))
        for i, c in enumerate(CHANNELS):
            assert series[c][k] == m[1 + i] and series[f"fresh_{c}"][k] == m.fresh[i], (k, c)


def test_warm_up_leaves_the_state_untouched():
    def first(b: SensorBank) -> tuple:
        return tuple(b.measure(k * 1e-3, sample()) for k in range(50))

    warmed = SensorBank("surface_rig", 1e-3, 2)
    warmed.warm_up()
    assert first(warmed) == first(SensorBank("surface_rig", 1e-3, 2))


def test_bad_times_and_values_are_refused_and_leave_the_state_intact():
    def run_good(b: SensorBank, ks) -> list:
        return [b.measure(k * 1e-3, sample(wob_n=1e5 + k)) for k in ks]

    clean, hit = SensorBank("mud_pulse", 1e-3, 1), SensorBank("mud_pulse", 1e-3, 1)
    expected = run_good(clean, range(200))
    got = run_good(hit, range(100))
    for t, s, words in ((float("nan"), sample(), "sensor time nan"),
                        (0.05, sample(), "not before the last call's"),
                        (float("inf"), sample(), "sensor time inf"),
                        (0.2, sample(tob_nm=float("nan")), "exact tob_nm = nan"),
                        (0.2, sample(wob_n=float("-inf")), "exact wob_n = -inf")):
        with pytest.raises(ParameterError, match="state is unchanged") as err:
            hit.measure(t, s)
        assert words in str(err.value)
    got += run_good(hit, range(100, 200))
    assert got == expected
    with pytest.raises(ParameterError, match="ascending"):
        hit.measure_series(np.array([0.5, 0.4]), {c: np.ones(2) for c in EXACT})
    with pytest.raises(ParameterError, match="exact wob_n = nan at row 1"):
        hit.measure_series(np.array([0.5, 0.6]), {**{c: np.ones(2) for c in EXACT},
                                                   "wob_n": np.array([1.0, np.nan])})


def test_a_delay_too_long_for_every_tick_sampling_is_refused_at_construction():
    profile = profile_from_dict("long", {"channels": {"tob_nm": {"delay_s": 1e4}}})
    with pytest.raises(ParameterError, match=r"channel tob_nm: delay_s = 10000 s .* more than"):
        SensorBank(profile, 1e-3)
    SensorBank(profile, 0.1)            # 1e5 samples at a 0.1 s tick: fine
