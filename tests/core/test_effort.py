"""The drive's effort and the settling (``core.effort``) against closed forms and a direct
computation of each definition, sample by sample; streamed in chunks it gives the same."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from drill_sim.core.effort import (
    BLOCK_S,
    EFFORT_KEYS,
    SETTLING_SSI,
    SETTLING_WINDOW_S,
    EffortStats,
    effort_figures,
)

H = 1e-3


def _sine(duration_s: float = 20.0, amplitude: float = 3000.0, mean: float = 5000.0,
          hz: float = 0.5):
    t = np.arange(0.0, duration_s + H / 2, H)
    return t, mean + amplitude * np.sin(2 * np.pi * hz * t)


def test_motor_figures_equal_the_closed_forms_of_a_sine():
    """RMS A/√2, p2p 2A, rate RMS 2πfA/√2, energy T̄ Ω t over whole periods: a figure of the
    wrong quantity (the torque itself, not its deviation; a rate without dt) fails."""
    t, torque = _sine()
    speed = np.full(t.size, 6.0)
    f = effort_figures(t, np.full(t.size, 6.0), torque, speed)
    assert f["motor_torque_rms_nm"] == pytest.approx(3000 / math.sqrt(2), rel=1e-4)
    assert f["motor_torque_p2p_nm"] == pytest.approx(6000.0, rel=1e-6)
    assert f["torque_rate_rms_nm_s"] == pytest.approx(2 * math.pi * 0.5 * 3000 / math.sqrt(2),
                                                      rel=1e-4)
    assert f["drive_energy_j"] == pytest.approx(5000.0 * 6.0 * 20.0, rel=1e-6)
    assert f["time_at_torque_limit_fraction"] is None          # no limits given
    assert f["settling_time_s"] is None                        # no event


def test_time_at_the_limit_is_the_share_of_a_clipped_sine_above_it():
    """A sine clipped at 0.5 of its amplitude sits on the upper limit (1/2 − arcsin(0.5)/π)
    of the time."""
    t, torque = _sine(mean=0.0, amplitude=1.0)
    clipped = np.clip(torque, -2.0, 0.5)
    f = effort_figures(t, np.ones(t.size), clipped, torque_limits_nm=(-2.0, 0.5))
    assert f["time_at_torque_limit_fraction"] == pytest.approx(
        0.5 - math.asin(0.5) / math.pi, abs=2e-3)


def _settling_by_definition(t, w, event_s):
    """The definition, directly: the earliest window start on the BLOCK_S grid after the
    event from which every SETTLING_WINDOW_S window of samples has SSI <= SETTLING_SSI."""
    starts = event_s + BLOCK_S * np.arange(0, int((t[-1] - event_s) / BLOCK_S) + 1)
    ok = []
    for s in starts:
        if s + SETTLING_WINDOW_S > t[-1] + 1e-9:
            break
        win = w[(t >= s - 1e-9) & (t < s + SETTLING_WINDOW_S - 1e-9)]
        ok.append((win.max() - win.min()) / (2 * win.mean()) <= SETTLING_SSI)
    settled = None
    for k in range(len(ok) - 1, -1, -1):
        if not ok[k]:
            break
        settled = starts[k] - event_s
    return settled


def test_settling_time_is_the_definition_and_the_decay_of_an_envelope():
    """A stick-slip-like oscillation decaying as e^{-t/τ} after a switch at 10 s: the settling
    time is the definition computed directly, and near τ ln(amplitude / threshold)."""
    t = np.arange(0.0, 60.0, H)
    tau, amp, event = 3.0, 1.2, 10.0
    env = np.where(t < event, amp, amp * np.exp(-(t - event) / tau))
    w = 6.0 * (1.0 + env * np.sin(2 * np.pi * 0.7 * t))
    w = np.maximum(w, 0.0)                           # the bit sticks while the envelope is big
    f = effort_figures(t, w, events_s=[event])
    direct = _settling_by_definition(t, w, event)
    assert f["settling_time_s"] == pytest.approx(direct, abs=BLOCK_S + 1e-9)
    assert f["settling_time_s"] == pytest.approx(tau * math.log(amp / SETTLING_SSI), abs=1.0)
    # an earlier set-point step changes nothing: the run settles after its last event
    assert effort_figures(t, w, events_s=[10.0, 2.0])["settling_time_s"] == f["settling_time_s"]


def test_no_settling_when_the_oscillation_never_decays_or_no_window_fits():
    t = np.arange(0.0, 30.0, H)
    w = 6.0 * (1.0 + 0.9 * np.sin(2 * np.pi * 0.7 * t))
    assert effort_figures(t, w, events_s=[5.0])["settling_time_s"] is None
    steady = np.full(t.size, 6.0)
    assert effort_figures(t, steady, events_s=[5.0])["settling_time_s"] == 0.0
    assert effort_figures(t, steady, events_s=[29.0])["settling_time_s"] is None


def test_chunks_give_the_whole_runs_figures_and_bad_torque_samples_are_left_out():
    """Streamed as a bag is read (uneven chunks), the figures equal the whole run's; a NaN
    torque sample is left out, as if it were not recorded."""
    t = np.arange(0.0, 30.0, H)
    w = 6.0 * (1.0 + np.exp(-t / 3.0) * np.sin(2 * np.pi * 0.7 * t))
    torque = 5000.0 + 2000.0 * np.sin(2 * np.pi * 0.3 * t)
    speed = 6.0 + np.cos(t)
    whole = effort_figures(t, w, torque, speed, torque_limits_nm=(0.0, 6500.0), events_s=[2.0])
    stats = EffortStats((0.0, 6500.0), [2.0])
    cuts = [0, 7, 1000, 1001, 5003, 17000, t.size]
    for lo, hi in itertools.pairwise(cuts):
        stats.add(t[lo:hi], w[lo:hi], torque[lo:hi], speed[lo:hi])
    chunked = stats.result()
    for key in EFFORT_KEYS:
        assert chunked[key] == pytest.approx(whole[key], rel=1e-9), key
    holed = torque.copy()
    holed[500] = np.nan
    f = effort_figures(t, w, holed, speed)
    keep = np.ones(t.size, bool)
    keep[500] = False
    g = effort_figures(t[keep], w[keep], torque[keep], speed[keep])
    assert f["motor_torque_rms_nm"] == pytest.approx(g["motor_torque_rms_nm"], rel=1e-12)
    assert f["torque_rate_rms_nm_s"] == pytest.approx(g["torque_rate_rms_nm_s"], rel=1e-12)


def test_samples_before_the_window_count_for_the_settling_only():
    t = np.arange(0.0, 30.0 + H / 2, H)
    torque = np.where(t < 10.0, 40000.0, 5000.0)
    f = effort_figures(t, np.full(t.size, 6.0), torque, np.full(t.size, 6.0),
                       events_s=[5.0], window_start_s=10.0)
    assert f["motor_torque_p2p_nm"] == 0.0
    assert f["drive_energy_j"] == pytest.approx(5000.0 * 6.0 * 20.0, rel=1e-6)
    assert f["settling_time_s"] == 0.0


def test_without_a_motor_torque_every_motor_figure_is_none_and_the_keys_are_all_there():
    t = np.arange(0.0, 10.0, H)
    f = effort_figures(t, np.full(t.size, 6.0))
    assert set(f) == set(EFFORT_KEYS)
    assert all(f[k] is None for k in EFFORT_KEYS)
