"""The rig session's semantics, in-process on ``RigSession`` (the object the node binds to
ROS and ``bag resim`` re-runs): command rules, pause/step/reset, run-time changes (all or
nothing), ``measured_publish``, the lockstep rule, and a recorded session re-simulated bit for
bit. What only a process can show (signals, crashes, two rigs, real time) stays in tests/ros."""

from __future__ import annotations

import itertools
import math

import pytest

from drill_sim.core import RPM, ParameterError, load_preset
from drill_sim.session.parameter_table import specs
from drill_sim.session.resim import resimulate
from drill_sim.session.rig_session import RigSession
from drill_sim.session.session_commands import IN_FLIGHT_S
from drill_sim.wire import cdr, cdr_decode, rig_topics

SPEED = rig_topics.topic("~/cmd/top_drive")
HOOK = rig_topics.topic("~/cmd/hook_load")
TORQUE = rig_topics.topic("~/cmd/top_drive_torque")
TWIST = cdr.stamped_vectors("top_drive")


class Clock:
    """A wall clock the test moves [s]."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture(scope="module")
def base():
    return load_preset("base")


def params(base, **changes) -> dict[str, object]:
    p = {s.name: s.default for s in specs(base)}
    p.update(publish_clock=True, max_speed=True, rate_hz=1000.0)
    p.update(changes)
    return p


def speed_command(session: RigSession, rad_s: float, frame: str = "top_drive"):
    stamp_ns = session.stamp_ns()
    sec, nsec = divmod(stamp_ns, 1_000_000_000)
    data = cdr.stamped_vectors(frame)(sec, nsec, (0, 0, 0, 0, 0, rad_s))
    return session.commands.receive(SPEED, data)


class Sent:
    """Publishers that keep what they were handed: ``got[k]``, the bytes of output k."""

    def __init__(self, session: RigSession) -> None:
        self.got: list[list[bytes]] = [[] for _ in session.outputs]
        self.send = [lst.append for lst in self.got]


# ---- commands --------------------------------------------------------------------------
def test_an_accepted_command_is_held_from_the_next_tick(base):
    s = RigSession(params(base))
    assert speed_command(s, 70 * RPM) is None
    assert s.rig.commanded_speed_rad_s == pytest.approx(70 * RPM, rel=0, abs=1e-15)
    assert s.tick()
    assert s.rig.sample().top_drive_speed_rad_s == pytest.approx(70 * RPM)


@pytest.mark.parametrize(("value", "frame", "words"), [
    (math.nan, "top_drive", "finite value"),
    (-1.0, "top_drive", "finite value"),
    (1e9, "top_drive", "finite value"),
    (5.0, "world", "'top_drive' or empty"),
])
def test_a_refused_command_leaves_the_rig_untouched(base, value, frame, words):
    s = RigSession(params(base))
    held = s.rig.commanded_speed_rad_s
    refusal = speed_command(s, value, frame)
    assert refusal is not None and words in refusal[2]
    assert s.rig.commanded_speed_rad_s == held


def test_bytes_that_do_not_decode_are_refused(base):
    s = RigSession(params(base))
    refusal = s.commands.receive(SPEED, b"\x00\x01\x00\x00abc")
    assert refusal is not None and "CDR" in refusal[2]


def test_a_torque_command_needs_torque_mode_and_one_in_flight_is_dropped(base):
    clock = Clock()
    s = RigSession(params(base, top_drive_mode="torque"), clock=clock)
    data = TWIST(0, 0, (0, 0, 0, 0, 0, 1000.0))
    assert s.commands.receive(TORQUE, data) is None
    s.change(dict(s.p, top_drive_mode="speed"))
    clock.now += 0.3                                        # sent 0.3 s before it came
    assert s.commands.receive(TORQUE, data) == "in flight"          # crossed the switch on the way
    clock.now += IN_FLIGHT_S - 0.3 + 0.01
    refusal = s.commands.receive(TORQUE, data)
    assert refusal != "in flight" and "top_drive_mode = torque" in refusal[2]


# ---- pause, step, reset ----------------------------------------------------------------
def test_paused_nothing_advances_and_step_advances_exactly_one_tick(base):
    s = RigSession(params(base, start_paused=True))
    out = Sent(s)
    assert not s.tick(out.send) and s.sim_time_s == 0.0
    assert s.step(out.send) == (True, "stepped to t = 0.001000 s")
    assert s.sim_time_s == pytest.approx(1e-3, abs=1e-15)
    assert len(out.got[0]) == 1
    assert s.pause(False) == "running"
    assert s.step(out.send)[0] is False                     # only while paused


def test_reset_starts_again_and_simulated_time_goes_on(base):
    s = RigSession(params(base))
    start = s.rig.sample()
    speed_command(s, 90 * RPM)
    for _ in range(200):
        s.tick()
    assert s.rig.sample().top_drive_speed_rad_s != start.top_drive_speed_rad_s
    done, message = s.reset(Sent(s).send)
    assert done and "initial state" in message
    again = s.rig.sample()
    assert again.bit_speed_rad_s == start.bit_speed_rad_s
    assert s.sim_time_s == pytest.approx(0.2, abs=1e-12)    # the stamps keep counting


# ---- run-time changes ------------------------------------------------------------------
def test_a_refused_change_leaves_the_session_as_it_was(base):
    s = RigSession(params(base))
    before = dict(s.p)
    drive = s.rig.top_drive
    with pytest.raises(ParameterError):
        s.change(dict(s.p, rate_hz=333.0))                   # not a whole number of steps
    assert s.p == before and s.rig.top_drive == drive
    changed = s.change(dict(s.p, rate_hz=500.0))
    assert changed == {"rate_hz"} and s.steps_per_tick == 20     # 100 us steps
    s.tick()
    assert s.sim_time_s == pytest.approx(2e-3, abs=1e-15)


# ---- what is published -----------------------------------------------------------------
def test_measured_on_sample_sends_a_measured_topic_only_when_fresh(base):
    """surface_rig samples the surface at 100 Hz: at 1 kHz ticks its surface topics go out
    every 10th tick with on_sample, every tick with every_tick."""
    for mode, period_ns in (("every_tick", 1_000_000), ("on_sample", 10_000_000)):
        s = RigSession(params(base, sensor_profile="surface_rig", measured_publish=mode))
        out = Sent(s)
        k = [t.name for t in s.outputs].index("~/measured/top_drive/twist")
        for _ in range(100):
            s.tick(out.send)
        stamps = [cdr_decode.decode_stamped_vectors(raw)[1] * 10**9
                  + cdr_decode.decode_stamped_vectors(raw)[2] for raw in out.got[k]]
        assert len(stamps) >= 100_000_000 // period_ns - 1, mode
        assert {b - a for a, b in itertools.pairwise(stamps)} == {period_ns}, mode
        assert len(out.got[0]) == 100                        # exact outputs: every tick


def test_lockstep_holds_the_tick_until_every_topic_answers_its_stamp(base):
    s = RigSession(params(base, lockstep=True, lockstep_topics=["cmd/top_drive",
                                                                "cmd/hook_load"]))
    s.advance(1)
    stamp = s.emit(Sent(s).send)                            # the tick at 1 ms waits
    ls = s.lockstep
    assert not ls.complete
    sec, nsec = divmod(stamp, 1_000_000_000)
    receive = s.commands.receive
    receive(SPEED, TWIST(sec, nsec + 1, (0, 0, 0, 0, 0, 6.0)))     # not this tick's stamp,
    receive(HOOK, TWIST(sec, nsec + 1, (0, 0, 5e5, 0, 0, 0)))      # later ones
    receive(SPEED, TWIST(sec, nsec - 1, (0, 0, 0, 0, 0, 6.0)))     # nor an earlier one
    assert not ls.complete
    receive(SPEED, TWIST(sec, nsec, (0, 0, 0, 0, 0, 6.0)))
    assert not ls.complete                                  # the hook load has not answered
    receive(HOOK, TWIST(sec, nsec, (0, 0, 5e5, 0, 0, 0)))
    assert ls.complete


# ---- recording and re-simulation -------------------------------------------------------
def test_a_recorded_session_resimulates_bit_for_bit(base, tmp_path):
    """Commands (one refused), a run-time change of the rock, a reset and noisy sensors:
    ``bag resim`` re-runs the bag through a new session and every sample, exact and measured,
    equals the recording."""
    bag = tmp_path / "session"
    s = RigSession(params(base, record=str(bag), sensor_profile="surface_rig",
                          sensor_seed=7), preset="base")
    out = Sent(s)
    s.emit(out.send)
    for k in range(1, 601):
        if k == 100:
            speed_command(s, 80 * RPM)
            speed_command(s, math.nan)
        if k == 250:
            s.change(dict(s.p, intrinsic_specific_energy_pa=1.3e8))
        if k == 400:
            s.reset(out.send)
        s.tick(out.send)
    s.close()
    result = resimulate(bag)
    assert result.exact, result.explanation()
    assert result.samples == 602 and result.commands == 1 and result.refused == 1
    assert result.events == ["parameters", "reset"]


def test_resimulation_notices_a_session_that_differs(base, tmp_path):
    """The same bag, one command left out of the re-run: the samples differ (so the exact
    comparison above can fail)."""
    bag = tmp_path / "session"
    s = RigSession(params(base, record=str(bag)), preset="base")
    for k in range(300):
        if k == 50:
            speed_command(s, 80 * RPM)
        s.tick()
    s.close()
    from drill_sim.session import resim
    real = resim._Rerun.command
    try:
        resim._Rerun.command = lambda self, topic, data: None
        result = resimulate(bag)
    finally:
        resim._Rerun.command = real
    assert not result.exact and result.max_difference["top_drive_speed_rad_s"] > 0.1


def test_the_figures_line_names_the_distributed_strings_own_first_mode(base):
    """The lumped model's torsional frequency is not the distributed string's: on it the line
    adds the pipe's own first mode (base: 0.555 Hz, the exact damped pipe's, top held)."""
    lumped = RigSession(params(base)).figures()
    assert "torsional 0.756 Hz" in lumped and "distributed" not in lumped
    line = RigSession(params(base, string_model="distributed"), geometry=base.string).figures()
    assert "the distributed string's first torsional mode 0.555 Hz (damping ratio 4.9 %)" in line
