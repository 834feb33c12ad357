"""The controller node's loop without ROS (drill_sim.control.sampled_loop): readings joined by
stamp, a gap caught up on interpolated readings, a repeated tick answered again, bad readings
skipped, and the status a controller reports."""

from __future__ import annotations

import math

import pytest

from drill_sim.control import LAWS, SurfaceMeasurement
from drill_sim.control.sampled_loop import (
    KEEP_PENDING,
    MAX_CATCH_UP,
    MOTOR,
    SETPOINT,
    SPEED,
    SURFACE,
    SampledLoop,
    controller_status,
)
from drill_sim.control.supervisor import Supervisor, law_gain_defaults
from drill_sim.core.top_drive import TopDriveParameters

H, Z, J = 1e-3, 302.4, 2900.0
NS = 1_000_000                        # one period h in ns
W = 2 * math.pi


def supervisor() -> Supervisor:
    return Supervisor(H, Z, J, "stiff_pi", speed_set_rad_s=W)


def test_readings_are_joined_by_stamp_whatever_their_order():
    loop = SampledLoop()
    assert loop.put(2 * NS, SPEED, 6.0) is None
    assert loop.put(NS, SURFACE, 3.0) is None
    assert loop.put(NS, SPEED, 1.0) is None
    assert loop.put(NS, MOTOR, 2.0) == [1.0, 2.0, 3.0]
    assert loop.put(2 * NS, MOTOR, 7.0) is None
    assert loop.put(2 * NS, SURFACE, 8.0) == [6.0, 7.0, 8.0]


def test_a_complete_tick_drops_the_older_incomplete_ones():
    loop = SampledLoop()
    loop.put(NS, SPEED, 1.0)
    for place in (SPEED, MOTOR, SURFACE):
        loop.put(2 * NS, place, 1.0)
    loop.put(NS, MOTOR, 2.0)
    assert loop.put(NS, SURFACE, 3.0) is None        # its speed was forgotten with the tick


def test_readings_that_never_complete_are_forgotten_the_oldest_first():
    loop = SampledLoop()
    for k in range(KEEP_PENDING + 1):
        loop.put(k * NS, SPEED, 1.0)
    assert len(loop._pending) == KEEP_PENDING + 1          # up to here all are kept
    loop.put((KEEP_PENDING + 1) * NS, SPEED, 1.0)         # one more: the oldest go
    assert sorted(loop._pending) == [k * NS for k in range(KEEP_PENDING // 2 + 1,
                                                           KEEP_PENDING + 2)]


def test_a_gap_is_caught_up_on_readings_interpolated_from_the_previous_tick():
    loop, core = SampledLoop(), supervisor()
    twin = supervisor()
    first, later = [W - 0.1, 5e3, 4e3], [W + 0.2, 8e3, 7e3]
    start = 7                                           # the loop's first tick: 7 h
    out0, _ = loop.step(core, start * NS, first)
    assert out0 == twin.step(SurfaceMeasurement(start * H, *first))
    out, why = loop.step(core, (start + 3) * NS, later)      # two ticks never came
    assert why == ""
    for k in (1, 2, 3):                                 # by hand: a third, two thirds, all
        f = k / 3
        between = [a + f * (b - a) for a, b in zip(first, later, strict=True)]
        expected = twin.step(SurfaceMeasurement((start + k) * H, *between))
    assert out == pytest.approx(expected, rel=1e-12)
    assert core.samples == 4


def test_a_long_gap_is_caught_up_at_most_max_catch_up_steps():
    loop, core = SampledLoop(), supervisor()
    loop.step(core, 0, [W, 5e3, 5e3])
    loop.step(core, 10 * MAX_CATCH_UP * NS, [W, 5e3, 5e3])
    assert core.samples == 1 + MAX_CATCH_UP


def test_a_tick_seen_again_gets_the_same_answer_without_a_step():
    loop, core = SampledLoop(), supervisor()
    loop.step(core, 0, [W, 5e3, 5e3])
    out, _ = loop.step(core, NS, [W - 0.5, 5e3, 5e3])
    again, _ = loop.step(core, NS, [W - 0.5, 5e3, 5e3])
    assert again == out and core.samples == 2
    core.set_enabled(False)
    assert loop.step(core, NS, [W - 0.5, 5e3, 5e3]) == (None, "")   # disabled: nothing sent


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_a_non_finite_reading_skips_the_tick_and_says_when(bad):
    loop, core = SampledLoop(), supervisor()
    out, why = loop.step(core, 2_500 * NS, [W, bad, 5e3])
    assert (out, why) == (None, "sample at 2.500 s skipped: non-finite input")
    assert core.samples == 0 and loop.last is None


def test_a_ticks_set_point_is_applied_before_its_step():
    loop, core = SampledLoop(with_setpoint=True), supervisor()
    assert loop.size == 4
    readings = [None] * 4
    for place, value in ((SPEED, W), (MOTOR, 5e3), (SURFACE, 5e3), (SETPOINT, 2 * W)):
        readings = loop.put(0, place, value)
    out, _ = loop.step(core, 0, readings)
    twin = supervisor()
    twin.set_speed(2 * W)
    assert core.speed_set_rad_s == 2 * W
    assert out == twin.step(SurfaceMeasurement(0.0, W, 5e3, 5e3))


def test_the_status_names_what_is_wrong():
    core = supervisor()
    quiet = {"samples": 0, "saturation_fraction": 0.0, "windup_fraction": 0.0}
    busy = {"samples": 100, "saturation_fraction": 0.1, "windup_fraction": 0.0}
    assert controller_status(core, busy, False, "/r") == (True, "waiting for /r's rate_hz")
    assert controller_status(core, quiet, True, "/r") == (
        True, "no samples: the rig's inputs are not arriving")
    half = {**busy, "saturation_fraction": 0.5, "windup_fraction": 0.5}
    assert controller_status(core, half, True, "/r") == (False, "controlling")  # "over half"
    assert controller_status(core, busy, True, "/r") == (False, "controlling")
    assert controller_status(core, {**busy, "saturation_fraction": 0.6}, True, "/r") == (
        True, "output saturated")
    assert controller_status(core, {**busy, "windup_fraction": 0.6}, True, "/r")[0] is True
    core.set_enabled(False)
    assert controller_status(core, quiet, True, "/r") == (False, "disabled")


def test_gain_defaults_are_numbers_with_the_base_drives_limits():
    drive = TopDriveParameters()
    for law in ("stiff_pi", "z_torque"):                  # K_p, K_i left to Z and J_TD
        gains = law_gain_defaults(law, Z, 1000.0)
        assert gains["kp_nm_s_rad"] == 50.0 * Z and gains["ki_nm_rad"] == 5.0 * 1000.0
    for law in ("stiff_pi", "soft_speed", "z_torque"):
        gains = law_gain_defaults(law, Z, J)
        assert set(gains) == set(LAWS[law].GAINS)
        assert gains["torque_max_nm"] == drive.motor_torque_max_nm
        assert gains["torque_min_nm"] == drive.motor_torque_min_nm
        assert all(math.isfinite(v) for v in gains.values())
        Supervisor(H, Z, J, law, gains)                  # the law takes them
