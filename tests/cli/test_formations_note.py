"""The studies' stepper (``drill_sim simulate``, ``map``) keeps one rock: with a preset whose
well has formations it says so on stderr rather than ignore them without a word."""

from __future__ import annotations

from dataclasses import replace

from drill_sim.cli.case import Case
from drill_sim.cli.single import formations_note
from drill_sim.core import load_preset
from drill_sim.core.well import Formation, Well


def test_a_preset_with_formations_gets_a_note(capsys):
    base = load_preset("base")
    layered = replace(base, string=replace(base.string, well=Well(formations=(
        Formation(1200.0, friction_coefficient=0.4),))))
    formations_note(Case(base.rig.groups, 9.6, 1.3, base), "drill_sim simulate")
    assert capsys.readouterr().err == ""
    formations_note(Case(base.rig.groups, 9.6, 1.3, layered), "drill_sim simulate")
    assert capsys.readouterr().err == (
        "drill_sim simulate: note: the preset's 1 formation along the hole is not followed here "
        "(one rock throughout: its bit section's); the node, drill_sim run and drill_sim "
        "control follow them\n")
