"""Formations in a rig session (the node's object): followed, recorded as events, and
re-simulated exactly from the bag (its ``string`` record keeps them, lumped string too)."""

from __future__ import annotations

from dataclasses import replace

from drill_sim.core import load_preset
from drill_sim.core.well import Formation, Well
from drill_sim.session.parameter_table import specs
from drill_sim.session.resim import resimulate
from drill_sim.session.rig_session import RigSession


def test_a_session_crossing_a_formation_records_it_and_resimulates_bit_for_bit(
        tmp_path):
    """The rig session (the node's object) follows the formation, says so in its bag's
    events, and ``bag resim`` re-runs the bag through the same formations exactly."""
    base_preset = load_preset("base")
    start = base_preset.string.length_m
    geometry = replace(base_preset.string, well=Well(formations=(
        Formation(start + 0.005, intrinsic_specific_energy_pa=150e6),)))
    p = {s.name: s.default for s in specs(base_preset)}
    p.update(publish_clock=True, max_speed=True, record=str(tmp_path / "bag"))
    session = RigSession(p, geometry=geometry, preset="base")
    ticks = 0
    while session.rig.layer < 0:
        session.tick()
        ticks += 1
        assert ticks < 3000, "the bit never reached the formation"
    for _ in range(200):
        session.tick()
    session.close()
    result = resimulate(tmp_path / "bag")
    assert result.exact, result.explanation()
    assert result.events == ["formation"]
