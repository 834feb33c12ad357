"""The lockstep rule without ROS (msg_docs/node.md, "Lockstep"): a tick is released only by a
command stamped with its own time on every lockstep topic; other stamps and other topics never
release it; a wait is reported once per timeout and never ends by itself; /diagnostics warns
about it and about stalled real-time ticks."""

from __future__ import annotations

import pytest

from drill_sim.core import load_preset
from drill_sim.core.rig import Rig
from drill_sim.session.diagnostics import OK, WARN, rig_status
from drill_sim.session.lockstep import Lockstep
from drill_sim.session.pacing import TickStats
from drill_sim.session.parameter_table import specs
from drill_sim.wire import rig_topics

TOP, HOOK = "~/cmd/top_drive", "~/cmd/hook_load"
QUIET = {"ssi": 0.0, "stick_fraction": 0.0, "bounce_fraction": 0.0}
RUNNING = {"paused": False, "record_error": None, "command_age_s": 0.2,
           "command_timeout_s": 1.0, "rate_hz": 1000.0, "sim_time_s": 12.5}


def test_a_tick_is_released_only_by_its_own_stamp_on_every_topic():
    ls = Lockstep((TOP, HOOK), timeout_s=1.0)
    assert not ls.complete                        # nothing published yet: nothing to release
    ls.wait_for(5_000_000, now_s=0.0)
    assert not ls.offer(TOP, 4_000_000)           # a late answer to tick 4 ms
    assert not ls.offer(TOP, 6_000_000)           # a stamp from the future
    assert not ls.offer("~/cmd/other", 5_000_000)  # not a lockstep topic: not counted
    assert not ls.complete and ls.other_stamps == 2
    assert ls.offer(TOP, 5_000_000) and not ls.complete   # the hook load is still missing
    assert not ls.offer(TOP, 5_000_000)           # a second answer counts as another stamp
    assert ls.offer(HOOK, 5_000_000) and ls.complete
    ls.wait_for(6_000_000, now_s=0.001)           # the next tick starts empty
    assert not ls.complete and set(ls.missing) == {TOP, HOOK}


def test_the_drives_lockstep_topic_follows_its_mode_and_an_answered_tick_stays_answered():
    """A drive switched to speed at run time answers on ~/cmd/top_drive, to torque on
    ~/cmd/top_drive_torque: the wait moves with it; other lockstep topics stay; a tick still
    waiting for the drive waits on the new topic; one answered before the switch stays
    answered. Two drive topics listed: nothing moves."""
    torque = "~/cmd/top_drive_torque"
    ls = Lockstep((torque, HOOK), timeout_s=1.0)
    ls.wait_for(1_000_000, now_s=0.0)
    ls.follow_drive_mode("speed")
    assert ls.topics == (TOP, HOOK) and ls.missing == {TOP, HOOK}
    assert not ls.offer(torque, 1_000_000)        # the torque topic no longer answers
    assert ls.offer(TOP, 1_000_000) and ls.offer(HOOK, 1_000_000) and ls.complete
    ls.wait_for(2_000_000, now_s=0.001)
    assert ls.offer(TOP, 2_000_000)
    ls.follow_drive_mode("torque")                # answered before the switch: stays so
    assert ls.topics == (torque, HOOK) and ls.missing == {HOOK}
    ls.follow_drive_mode("kinematic")
    assert ls.topics == (TOP, HOOK)
    both = Lockstep((TOP, torque), timeout_s=1.0)
    both.follow_drive_mode("speed")
    assert both.topics == (TOP, torque)
    hook_only = Lockstep((HOOK,), timeout_s=1.0)
    hook_only.follow_drive_mode("torque")
    assert hook_only.topics == (HOOK,)


def test_a_wait_is_reported_once_per_timeout_and_never_ends_by_itself():
    ls = Lockstep((TOP,), timeout_s=0.5)
    ls.wait_for(0, now_s=10.0)
    assert ls.until_overdue(10.1) == pytest.approx(0.4)
    reports = [t for t in (10.2, 10.4, 10.5, 10.6, 10.9, 11.0, 11.2) if ls.overdue(t)]
    assert reports == [10.5, 11.0]
    assert not ls.complete
    status = ls.status(11.2)
    assert status.waiting_s == pytest.approx(1.2) and status.missing == (TOP,)
    ls.offer(TOP, 0)
    assert ls.complete and not ls.overdue(20.0) and ls.status(20.0).waiting_s == 0.0


@pytest.fixture(scope="module")
def steady():
    preset = load_preset("base")
    rig = Rig(preset.rig)
    rig.start_steady(preset.top_drive_speed_rad_s, preset.hook_load_n)
    return rig.sample()


def test_diagnostics_warn_about_a_long_lockstep_wait(steady):
    ls = Lockstep((TOP,), timeout_s=1.0)
    ls.wait_for(2_500_000_000, now_s=0.0)
    ticks = TickStats(ticks=0, wall_s=1.0, sim_s=0.0, period_p99_s=float("nan"), overruns=0)
    short = rig_status(steady, QUIET, ticks, **RUNNING, max_speed=True, lockstep=ls.status(0.5))
    assert short.level == OK and short.values["lockstep_waiting_s"] == "0.500"
    long = rig_status(steady, QUIET, ticks, **RUNNING, max_speed=True, lockstep=ls.status(3.0))
    assert long.level == WARN
    assert long.message == ("lockstep: waiting 3.0 s for ~/cmd/top_drive stamped 2.500000 s "
                            "(timeout 1 s)")


def test_diagnostics_count_and_flag_stalled_real_time_ticks(steady):
    stalled = TickStats(ticks=995, wall_s=1.0, sim_s=1.0, period_p99_s=1.1e-3, overruns=7,
                        period_max_s=12e-3, stalls=2, longest_stall_s=30e-3)
    status = rig_status(steady, QUIET, stalled, **RUNNING, max_speed=False)
    assert status.level == WARN and status.message.startswith(
        "2 ticks stalled in the last 1.0 s (longest 12.0 ms); the longest advanced its 11 "
        "missed ticks with one sample")
    short = TickStats(ticks=995, wall_s=1.0, sim_s=1.0, period_p99_s=1.1e-3, overruns=7,
                      period_max_s=3.2e-3, stalls=2, longest_stall_s=30e-3)
    assert rig_status(steady, QUIET, short, **RUNNING, max_speed=False).message.startswith(
        "2 ticks stalled in the last 1.0 s (longest 3.2 ms); their missed ticks published late")
    fast = rig_status(steady, QUIET, short, **RUNNING, max_speed=False, real_time_factor=2.0)
    assert "(longest 3.2 ms); the longest advanced its 6 ticks with one sample (above " \
        "real-time factor 1" in fast.message                 # 3.2 periods at factor 2
    assert (status.values["overruns"], status.values["longest_stall_ms"]) == ("7", "30.000")
    calm = TickStats(ticks=1000, wall_s=1.0, sim_s=1.0, period_p99_s=1.1e-3, overruns=7,
                     period_max_s=1.2e-3, stalls=0, longest_stall_s=30e-3)
    assert rig_status(steady, QUIET, calm, **RUNNING, max_speed=False).level == OK


def test_lockstep_topics_are_the_tables_command_topics():
    spec = next(s for s in specs(load_preset("base")) if s.name == "lockstep_topics")
    names = [t.name[2:] for t in rig_topics.COMMANDS]
    assert "cmd/top_drive_torque" in names
    assert spec.check(["cmd/top_drive_torque"]) == (["cmd/top_drive_torque"], None)
    assert spec.check(["~/cmd/top_drive", "cmd/hook_load"]) == (
        ["cmd/top_drive", "cmd/hook_load"], None)
    assert spec.check("cmd/top_drive") == (["cmd/top_drive"], None)
    for bad in (["cmd/nope"], [], ["cmd/top_drive", "cmd/top_drive"], [3], "bit/wrench"):
        why = spec.check(bad)[1]
        assert why == (f"lockstep_topics = {bad!r}: expected a list of one or more of "
                       f"{', '.join(names)}, each once"), why
