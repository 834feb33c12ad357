"""A scenario played by the rig session itself: every set-point, parameter change and
controller switch lands on exactly the tick of its simulated time however the ticks are
grouped by the wall clock, is recorded, and re-simulates bit for bit."""

from __future__ import annotations

import pytest

from drill_sim.core import RPM, ParameterError, load_preset
from drill_sim.session.parameter_table import checked_change, specs
from drill_sim.session.resim import resimulate
from drill_sim.session.rig_session import RigSession
from drill_sim.session.scenario import scenario_from_dict

SCENARIO = {"description": "a step in speed, a harder formation, a controller", "duration_s": 1.0,
            "points": [{"at_s": 0.0, "rpm": 60.0, "wob_kn": 100.0},
                       {"at_s": 0.1, "rpm": 80.0},
                       {"at_s": 0.3, "wob_kn": 120.0, "ramp": True}],
            "changes": [{"at_s": 0.25, "intrinsic_specific_energy_pa": 1.3e8}],
            "controller": {"law": "z_torque", "on_at_s": 0.4}}


@pytest.fixture(scope="module")
def base():
    return load_preset("base")


def params(base, **changes):
    p = {s.name: s.default for s in specs(base)}
    p.update(publish_clock=True, max_speed=True, rate_hz=1000.0)
    p.update(changes)
    return p


class Switch:
    """A controller that confirms a switch when told to."""

    def __init__(self) -> None:
        self.asked: list[tuple[str, float]] = []
        self.confirmed = False
        self.session: RigSession | None = None

    def __call__(self, law: str):
        self.asked.append((law, self.session.sim_time_s))
        return self

    def done(self) -> bool:
        return self.confirmed


def played(base, chunks: int, **extra) -> tuple[RigSession, list[tuple], Switch]:
    """500 ticks advanced ``chunks`` at a time (as a late wall clock groups them), a sample
    kept after each advance."""
    switch = Switch()
    s = RigSession(params(base, **extra), preset="base")
    switch.session = s
    by_name = {sp.name: sp for sp in specs(base)}
    s.play(scenario_from_dict("test", SCENARIO), switch, lambda old, ch: checked_change(
        by_name, old, ch))
    seen = []
    sends = [lambda raw: None] * len(s.outputs)
    for _ in range(500 // chunks):
        s.advance_and_emit(chunks, sends)
        seen.append((s.sim_time_s, s.rig.commanded_speed_rad_s, s.rig.commanded_hook_load_n,
                     s.p["intrinsic_specific_energy_pa"]))
    return s, seen, switch


def test_each_event_lands_on_the_tick_of_its_time(base):
    """An event at time T acts from T on: on the tick that leaves T, so the state after tick k
    (time k ms) shows what was due by (k - 1) ms."""
    _, seen, switch = played(base, 1)
    w_s = base.rig.submerged_weight_n
    for t, speed, hook, energy in seen:
        k = round(t * 1000)
        due_s = (k - 1) * 1e-3
        assert speed == pytest.approx((80.0 if k > 100 else 60.0) * RPM, rel=1e-15), k
        assert energy == (1.3e8 if k > 250 else base.rig.intrinsic_specific_energy_pa), k
        wob_n = 1e3 * (100.0 + 20.0 * min(due_s / 0.3, 1.0))     # ramp from 0 to 0.3 s
        assert hook == pytest.approx(w_s - wob_n, rel=1e-12), k
    # asked as the rig leaves 0.399 s, so the law answers the sample at 0.4 s
    assert switch.asked == [("z_torque", pytest.approx(0.399, abs=1e-12))]


def test_the_wall_clock_grouping_of_ticks_changes_nothing(base):
    """Ticks advanced one by one or seven at a time (a machine that stalls): the same
    session, tick for tick (the run that ended SSI 1.52 or 0.26 by when a change landed)."""
    one = played(base, 1)[0]
    seven = played(base, 5)[0]
    assert one.rig.sample() == seven.rig.sample()


def test_a_switch_holds_a_lockstep_sample_until_the_controller_confirms(base):
    s, _, switch = played(base, 1, lockstep=True)
    # played() ran past the switch without a lockstep loop; run one more switch by hand
    switch.confirmed = False
    s.switch_pending = switch
    assert s.tick() and s.sample_held and not s.release([lambda raw: None] * len(s.outputs))
    switch.confirmed = True
    assert s.release([lambda raw: None] * len(s.outputs)) and not s.sample_held


def test_a_change_the_node_would_refuse_is_refused_before_anything_runs(base):
    bad = dict(SCENARIO, changes=[{"at_s": 0.2, "intrinsic_specific_energy": 1e8}])
    s = RigSession(params(base))
    by_name = {sp.name: sp for sp in specs(base)}
    with pytest.raises(ParameterError, match="did you mean intrinsic_specific_energy_pa"):
        s.play(scenario_from_dict("bad", bad), None,
               lambda old, ch: checked_change(by_name, old, ch))
    ro = dict(SCENARIO, changes=[{"at_s": 0.2, "dt_s": 1e-5}])
    with pytest.raises(ParameterError, match="dt_s cannot change at run time"):
        s.play(scenario_from_dict("ro", ro), None,
               lambda old, ch: checked_change(by_name, old, ch))


def test_a_played_scenario_is_recorded_and_resimulates_exactly(base, tmp_path):
    bag = tmp_path / "played"
    switch = Switch()
    s = RigSession(params(base, record=str(bag), sensor_profile="surface_rig"), preset="base")
    switch.session = s
    switch.confirmed = True
    s.play(scenario_from_dict("test", SCENARIO), switch)
    sends = [lambda raw: None] * len(s.outputs)
    s.emit(sends)
    for _ in range(600):
        s.advance_and_emit(1, sends)
    s.close()
    result = resimulate(bag)
    assert result.exact, result.explanation()
    assert result.events == ["parameters", "controller"]
    assert result.commands >= 3 + 100      # two steps, the start, every tick of the ramp
