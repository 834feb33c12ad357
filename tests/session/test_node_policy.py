"""The node's rules without ROS: the diagnostics policy, the pacing of ticks (on a fake clock)
and the command rule the node and ``bag resim`` share."""

from __future__ import annotations

import itertools
import math
import random

import pytest

from drill_sim.core import RPM, Rig, load_preset
from drill_sim.session import rules
from drill_sim.session.diagnostics import (
    ERROR,
    OK,
    WARN,
    CommandCounts,
    drilling_regime,
    rig_status,
)
from drill_sim.session.pacing import CATCH_UP_TICKS, Pacer, TickStats
from drill_sim.session.parameter_table import specs


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture(scope="module")
def samples():
    """The base rig drilling steadily, stuck in stick-slip, and off bottom."""
    preset = load_preset("base")
    rig = Rig(preset.rig)
    weight = preset.rig.submerged_weight_n
    rig.start_steady(200 * RPM, weight - 80e3)
    steady = rig.sample()
    rig.start_steady(60 * RPM, weight - 100e3, perturbation=1e-3)
    rig.advance(30.0)
    while not rig.sample().stuck:
        rig.advance(1e-3)
    stuck = rig.sample()
    rig.command(60 * RPM, 1.2 * weight)
    rig.advance(2.0)
    return {"steady": steady, "stuck": stuck, "off": rig.sample()}


QUIET = {"ssi": 0.0, "stick_fraction": 0.0, "bounce_fraction": 0.0}
GOOD_TICKS = TickStats(ticks=1000, wall_s=1.0, sim_s=1.0, period_p99_s=1.05e-3, overruns=0,
                       period_max_s=1.2e-3)
RUNNING = {"paused": False, "record_error": None, "command_age_s": 0.2,
           "command_timeout_s": 1.0, "rate_hz": 1000.0, "max_speed": False, "sim_time_s": 12.5}


def _regime(ssi=0.0, stuck=False, off=0.0, now=False, speed=6.0) -> str:
    return drilling_regime(ssi=ssi, stuck=stuck, off_bottom_fraction=off, off_bottom_now=now,
                           top_drive_speed_rad_s=speed)


def test_drilling_regimes_and_their_thresholds():
    """The names an engineer uses, at the documented thresholds: a bit swinging 40-350 rpm
    (SSI 0.81) without stopping is a torsional oscillation, not steady drilling."""
    assert _regime() == "steady"
    assert _regime(ssi=0.099) == "steady"
    assert _regime(ssi=0.1) == "torsional oscillation"
    assert _regime(ssi=0.81) == "torsional oscillation"
    assert _regime(ssi=1.3, stuck=True) == "stick-slip"
    assert _regime(ssi=math.inf, stuck=True, speed=0.0) == "not rotating"
    assert _regime(ssi=1.3, stuck=True, off=0.02) == "bouncing"
    assert _regime(off=0.6, now=False) == "bouncing"
    assert _regime(off=0.5, now=True) == "off bottom"
    assert _regime(ssi=math.nan) == "steady"                 # an empty window


def test_regime_of_rig_states(samples):
    def status(name, **metrics):
        return rig_status(samples[name], dict(QUIET, **metrics), GOOD_TICKS, **RUNNING)
    assert status("steady").values["regime"] == "steady"
    assert status("stuck", ssi=1.2, stick_fraction=0.3).values["regime"] == "stick-slip"
    assert status("stuck").values["regime"] == "stick-slip"      # the stick-slip flag is up
    assert status("off", bounce_fraction=1.0).values["regime"] == "off bottom"


def test_a_healthy_rig_is_ok_with_every_value(samples):
    status = rig_status(samples["steady"], QUIET, GOOD_TICKS, **RUNNING,
                        commands=CommandCounts(120, 3, 0, 0))
    assert (status.level, status.message) == (OK, "steady")
    assert status.values == {
        "tick_rate_hz": "1000.0", "tick_period_p99_ms": "1.050", "tick_period_max_ms": "1.200",
        "overruns": "0", "longest_stall_ms": "0.000", "real_time_factor": "1.000",
        "regime": "steady", "ssi": "0.000",
        "stick_fraction": "0.000", "off_bottom_fraction": "0.000", "command_age_s": "0.200",
        "commands_received": "120", "commands_superseded": "3", "commands_lost": "0",
        "command_topics_with_several_publishers": "", "commands_refused": "0",
        "command_owners": "",
        "sim_time_s": "12.500", "paused": "false"}


def test_every_active_condition_is_listed_and_the_level_is_the_worst(samples):
    """A collapsed tick rate does not hide behind a stale command, nor either behind a
    recording error: all are listed, worst first."""
    s = samples["stuck"]
    slow = TickStats(ticks=300, wall_s=1.0, sim_s=0.3, period_p99_s=20e-3, overruns=30,
                     period_max_s=0.4)
    stale = dict(RUNNING, command_age_s=5.0)
    lost = CommandCounts(received=9000, superseded=8000, lost=40000, lost_in_window=12000)
    status = rig_status(s, QUIET, slow, **stale, commands=lost)
    assert status.level == WARN
    parts = status.message.split("; ")
    assert parts[0] == "tick rate 300 Hz below 1000 Hz"
    assert parts[1].startswith("12000 commands lost in the last 1.0 s")
    assert parts[2].startswith("no command for 5.0 s")
    status = rig_status(s, QUIET, slow, **dict(stale, record_error="recording stopped: full"))
    assert status.level == ERROR
    assert status.message.startswith("recording stopped: full; tick rate 300 Hz")
    assert ("no command received yet (5.0 s since start, timeout 1 s); holding the initial "
            "commands") in status.message                   # none ever came: says so
    status = rig_status(s, QUIET, slow, **dict(stale, paused=True))
    assert (status.level, status.message, status.values["paused"]) == (OK, "paused", "true")
    status = rig_status(s, QUIET, slow, **RUNNING)
    assert (status.level, status.message) == (WARN, "tick rate 300 Hz below 1000 Hz")
    assert status.values["regime"] == "stick-slip"
    assert status.values["tick_period_max_ms"] == "400.000"


def test_slow_ticks_warn_only_after_overruns_and_never_at_max_speed(samples):
    s = samples["steady"]
    few = TickStats(ticks=800, wall_s=1.0, sim_s=0.8, period_p99_s=math.nan, overruns=0)
    assert rig_status(s, QUIET, few, **RUNNING).level == OK
    late = TickStats(ticks=800, wall_s=1.0, sim_s=0.8, period_p99_s=math.nan, overruns=1)
    assert rig_status(s, QUIET, late, **dict(RUNNING, max_speed=True)).level == OK
    assert rig_status(s, QUIET, late, **RUNNING).values["tick_period_p99_ms"] == "nan"


def _dues(pacer: Pacer, clock: FakeClock, gaps_s) -> list[int]:
    """The ticks due at timer ticks ``gaps_s`` [s] apart."""
    out = []
    for gap in gaps_s:
        clock.now += gap
        out.append(pacer.due())
    return out


def test_real_time_pacing_advances_whole_ticks_despite_jitter():
    """At factor 1 every timer tick advances exactly one tick although the timer jitters by
    up to +-0.24 periods; over a run the ticks advanced equal the wall time x factor x rate."""
    rng = random.Random(3)
    clock = FakeClock()
    pacer = Pacer(1000.0, 1.0, False, window_s=1.0, rig_time_s=0.0, clock=clock)
    pacer.anchor()
    times = [k * 1e-3 + rng.uniform(-2.4e-4, 2.4e-4) for k in range(1, 2001)]
    gaps = [b - a for a, b in zip([0.0, *times], times, strict=False)]
    assert _dues(pacer, clock, gaps) == [1] * 2000
    for factor, per_tick in ((2.0, [2] * 6), (0.5, [1, 0, 1, 0, 1, 0]), (3.0, [3] * 6)):
        pacer.configure(1000.0, factor, False)
        assert _dues(pacer, clock, [1e-3] * 6) == per_tick, factor


def test_a_stalled_tick_advances_the_ticks_it_missed_and_is_counted():
    clock = FakeClock()
    pacer = Pacer(1000.0, 1.0, False, window_s=1.0, rig_time_s=0.0, clock=clock)
    dues = []
    for gap in [1e-3] * 5 + [4.6e-3] + [1e-3] * 5:      # the 6th tick came 3.6 ms late
        clock.now += gap
        pacer.tick_started()
        dues.append(pacer.due())
        pacer.advanced(dues[-1])
    assert dues == [1] * 5 + [5] + [1] * 5                # 4 missed ticks caught up, not more
    stats = pacer.window(0.015)
    assert (stats.overruns, stats.stalls) == (1, 1)
    assert stats.longest_stall_s == pytest.approx(4.6e-3)
    assert pacer.window(0.015).stalls == 0                # counted in its window only


def _wake_at_next_tick(pacer: Pacer, clock: FakeClock, lateness_s) -> list[int]:
    """The node's real-time loop on a fake clock: sleep until ``next_tick_s``, wake up
    ``lateness_s`` [s] late (one value per wake-up), advance what is due."""
    dues = []
    for late in lateness_s:
        clock.now = max(clock.now, pacer.next_tick_s()) + late
        pacer.tick_started()
        dues.append(pacer.due())
        pacer.advanced(dues[-1])
    return dues


def test_a_loop_waking_at_next_tick_advances_one_tick_a_wake_up():
    """Woken up to 0.45 periods late at random, the loop advances exactly one tick a wake-up,
    also after a stall (which advances the ticks it missed, once), and at other real-time
    factors the ticks of a period (at most one wake-up a period); simulated time follows the
    wall clock. A loop with a grid of its own drifted
    off the pacer's after the stall, and the same jitter advanced 0 ticks, then 2."""
    rng = random.Random(5)
    clock = FakeClock()
    pacer = Pacer(1000.0, 1.0, False, window_s=1.0, rig_time_s=0.0, clock=clock)
    start = clock.now
    lateness = [rng.uniform(0.0, 4.5e-4) for _ in range(3000)]
    lateness[1000] = 3.6e-3               # a stall, 3.6 periods late: its tick and 4 missed
    dues = _wake_at_next_tick(pacer, clock, lateness)
    assert dues[1000] == 5 and dues[:1000] == [1] * 1000 and dues[1001:] == [1] * 1999
    assert abs(sum(dues) - (clock.now - start) * 1000.0) <= 1.0    # on the wall clock
    for factor, ticks, period_s in ((2.0, 2, 1e-3), (0.5, 1, 2e-3), (1.5, 2, 4e-3 / 3),
                                    (3.0, 3, 1e-3)):
        pacer.configure(1000.0, factor, False)
        _wake_at_next_tick(pacer, clock, [0.0])           # anchors: the ticks of 1/rate_hz
        woken = []
        for _ in range(200):
            woken.append(pacer.next_tick_s())
            late = rng.uniform(0.0, 0.45e-3 / factor)      # up to 0.45 ticks of wall time
            assert _wake_at_next_tick(pacer, clock, [late]) == [ticks], factor
        assert woken[-1] - woken[-2] == pytest.approx(period_s)
    pacer.configure(1000.0, 1.0, True)
    assert pacer.next_tick_s() == clock.now                 # max speed: always now


def test_each_tick_of_a_short_stall_gets_its_own_sample():
    """After a stall of up to CATCH_UP_TICKS ticks each tick is advanced and published on
    its own (no gap in the samples); a longer stall, factors above 1 (ceil(factor) ticks a
    wake-up) and max speed advance with one sample."""
    pacer = Pacer(1000.0, 1.0, False, window_s=1.0, rig_time_s=0.0, clock=FakeClock())
    assert pacer.samples(0) == () and pacer.samples(1) == (1,)
    assert pacer.samples(3) == (1, 1, 1)
    assert pacer.samples(CATCH_UP_TICKS) == (1,) * CATCH_UP_TICKS
    assert pacer.samples(CATCH_UP_TICKS + 1) == (CATCH_UP_TICKS + 1,)
    pacer.configure(1000.0, 0.5, False)
    assert pacer.samples(2) == (1, 1)
    pacer.configure(1000.0, 2.0, False)
    assert pacer.samples(2) == (2,) and pacer.samples(4) == (4,)
    pacer.configure(1000.0, 1.0, True)
    assert pacer.samples(1) == (1,)


def test_real_time_pacing_drops_a_long_backlog():
    clock = FakeClock()
    pacer = Pacer(1000.0, 2.0, False, window_s=1.0, rig_time_s=0.0, clock=clock)
    assert _dues(pacer, clock, [1e-3, 1e-3]) == [2, 2]    # twice real time
    clock.now += 1.0                                       # a long stall: 2 s behind
    assert pacer.due() == 201                              # at most 0.1 s x factor + a tick
    assert _dues(pacer, clock, [1e-3, 1e-3]) == [2, 2]    # then on from there
    assert pacer.tick_s == pytest.approx(0.001)           # a tick is 1/rate_hz in every mode


def test_max_speed_pacing_advances_one_tick_per_call():
    pacer = Pacer(100.0, 3.0, True, window_s=1.0, rig_time_s=5.0, clock=FakeClock())
    assert [pacer.due() for _ in range(3)] == [1, 1, 1]
    assert pacer.tick_s == pytest.approx(0.01)        # what ~/step advances: one tick


def test_the_step_divides_the_tick():
    """A tick is a whole number of steps, the largest step not above dt_s (so the model's
    stability limit holds): 1 ms at 105 us is ten steps of 100 us, not nine (0.947 ms)."""
    for rate_hz, dt_s, steps in ((1000.0, 1.05e-4, 10), (100.0, 1.05e-4, 96),
                                 (5000.0, 1.05e-4, 2), (1000.0, 1e-4, 10), (1000.0, 5e-3, 1)):
        p = {"rate_hz": rate_hz, "dt_s": dt_s}
        step = rules.step_s(p)
        assert step <= dt_s and steps * step == pytest.approx(1.0 / rate_hz, rel=1e-15)
        assert round(1.0 / (rate_hz * step)) == steps
    rig = rules.make_rig({**{s.name: s.default for s in specs(load_preset("base"))},
                            "rate_hz": 1000.0})
    for k in range(1, 4):
        rig.advance_steps(10)
        assert round(rig.time_s * 1e9) == k * 1_000_000   # exactly 1 ms a tick, in ns
    assert rules.tick_refusal(500.0, 1e-4) is None and rules.tick_refusal(2000.0, 1e-4) is None
    assert "whole number of the session's step" in rules.tick_refusal(3000.0, 1e-4)


def test_tick_statistics_over_a_window():
    clock = FakeClock()
    pacer = Pacer(1000.0, 1.0, False, window_s=1.0, rig_time_s=0.0, clock=clock)
    for k in range(100):
        clock.now += 0.002 if k == 50 else 0.001             # one overrun (> 1.5 periods)
        pacer.tick_started()
        pacer.advanced(1)
    stats = pacer.window(0.1)
    assert (stats.ticks, stats.overruns) == (100, 1)
    assert stats.wall_s == pytest.approx(0.101)
    assert stats.rate_hz == pytest.approx(100 / 0.101)
    assert stats.real_time_factor == pytest.approx(0.1 / 0.101)
    assert 1e-3 <= stats.period_p99_s <= 2e-3
    assert stats.period_max_s == pytest.approx(2e-3)
    clock.now += 0.5
    pacer.reset(0.0)                                          # the rig restarted at 0 s
    stats = pacer.window(0.25)
    assert stats.ticks == 0 and math.isnan(stats.period_p99_s) and stats.overruns == 1
    assert math.isnan(stats.period_max_s)
    assert stats.sim_s == pytest.approx(0.25)


def test_max_speed_ticks_never_overrun():
    clock = FakeClock()
    pacer = Pacer(1000.0, 1.0, True, window_s=1.0, rig_time_s=0.0, clock=clock)
    for _ in range(3):
        clock.now += 0.05
        pacer.tick_started()
    assert pacer.overruns == 0
    pacer.configure(1000.0, 1.0, False)
    clock.now += 0.05
    pacer.tick_started()
    assert pacer.overruns == 1


def test_command_rule_takes_its_field_and_limit():
    preset = load_preset("base")
    p = {"max_top_drive_speed_rad_s": 30.0, "max_hook_load_n": 1e6}
    rig = Rig(preset.rig)
    rig.start_at_rest(0.0)
    six = (0.0, 0.0, 2e5, 0.0, 0.0, 7.0)
    assert rules.apply_command(rig, p, "top_drive", "top_drive", six) is None
    assert (rig.commanded_speed_rad_s, rig.commanded_hook_load_n) == (7.0, preset.rig
                                                                      .submerged_weight_n)
    assert rules.apply_command(rig, p, "hook_load", "", six) is None
    assert (rig.commanded_speed_rad_s, rig.commanded_hook_load_n) == (7.0, 2e5)
    refused = rules.apply_command(rig, p, "top_drive", "bit", six)
    assert refused == ("top-drive speed twist.angular.z frame_id", "bit", "'top_drive' or empty")
    too_fast = (0.0, 0.0, 0.0, 0.0, 0.0, 31.0)
    what, value, expected = rules.apply_command(rig, p, "top_drive", "", too_fast)
    assert (what, value) == ("top-drive speed twist.angular.z [rad/s]", 31.0)
    assert "[0, 30] rad/s" in expected
    assert rules.apply_command(rig, p, "hook_load", "", (0.0, 0.0, math.nan) + (0.0,) * 3)
    assert (rig.commanded_speed_rad_s, rig.commanded_hook_load_n) == (7.0, 2e5)  # held


def test_the_steady_start_turns_into_stick_slip_as_node_md_says():
    """The node's steady start (rules.start: no perturbation) on base at 60 rpm and 100 kN:
    round-off grows into a first stick after ~12 s, then a 1.57 s stick-slip cycle."""
    preset = load_preset("base")
    p = {"initial_top_drive_speed_rad_s": 60 * RPM, "initial_weight_on_bit_n": 100e3,
         "initial_state": "steady"}
    rig = Rig(preset.rig)
    rules.start(rig, p)
    onsets, was_stuck, k = [], False, 0
    while len(onsets) < 4:
        k += 1
        rig.advance_to(k * 1e-3)
        stuck = rig.sample().stuck
        if stuck and not was_stuck:
            onsets.append(k * 1e-3)
        was_stuck = stuck
    assert 11.0 < onsets[0] < 13.5
    periods = [b - a for a, b in itertools.pairwise(onsets[1:])]
    assert all(p == pytest.approx(1.57, abs=0.03) for p in periods)


def test_a_short_stall_samples_each_tick_and_a_long_one_all_at_once():
    """Up to CATCH_UP_TICKS missed ticks each keep their sample (published late); a longer
    stall advances its ticks with one sample (publishing hundreds back to back would delay
    the next ticks further)."""
    pacer = Pacer(1000.0, 1.0, False, 1.0, 0.0)
    assert pacer.samples(5) == (1,) * 5                  # 5 ticks: the documented limit
    assert pacer.samples(8) == (8,)
    assert pacer.samples(1) == (1,) and pacer.samples(0) == ()
