"""The one definition of the SSI and of a stuck bit (``core/stick_slip.py``), on records whose
answers are worked by hand, and its use by the places that judge a run."""

import math

import numpy as np
import pytest

from drill_sim.core.stick_slip import severity_index, stuck


def test_ssi_is_the_spread_over_twice_the_mean():
    # a stick-slip-like record: stuck a third of the time, then a burst to 3 rad/s
    speed = np.array([0.0, 0.0, 0.0, 1.0, 3.0, 2.0])
    mean = 1.0
    assert severity_index(speed.max(), speed.min(), speed.mean()) == pytest.approx(
        (3.0 - 0.0) / (2.0 * mean))
    assert severity_index(2.0, 2.0, 2.0) == 0.0              # steady rotation
    assert severity_index(3.0, 0.0, 1.5) == 1.0              # the bit just stops: SSI 1


def test_ssi_of_a_bit_that_never_turns_is_infinite():
    assert severity_index(0.0, 0.0, 0.0) == math.inf


def test_stuck_needs_the_bit_still_and_pressed_on_the_rock():
    speed = np.array([0.0, 0.0, 1e-12, 2.0])
    wob = np.array([5e4, 0.0, 5e4, 5e4])
    # still on the rock; still off bottom (bouncing); barely turning; drilling
    assert stuck(speed, wob).tolist() == [True, False, False, False]
    assert stuck(0.0, 1.0) and not stuck(0.0, 0.0)


def test_a_bags_metrics_use_it():
    """The bag's running metrics: stick fraction counts only still-and-pressed samples."""
    from drill_sim.bag.rig_stats import RigStats
    stats = RigStats("/t")
    t = np.arange(4.0)
    stats.add(t, {"bit_speed_rad_s": np.array([0.0, 0.0, 2.0, 2.0]),
                  "wob_n": np.array([1e4, 0.0, 1e4, 1e4]), "tob_nm": np.zeros(4),
                  "surface_torque_nm": np.zeros(4), "rop_m_s": np.zeros(4)})
    r = stats.result()
    assert r["stick_fraction"] == 0.25 and r["bounce_fraction"] == 0.25
    assert r["ssi"] == pytest.approx(2.0 / (2.0 * 1.0))
