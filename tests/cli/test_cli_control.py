"""``drill_sim control`` as a user types it: one JSON object with a row per law, the table it
writes, its figure, and one-line refusals of bad options."""

from __future__ import annotations

import csv
import json
import subprocess

import pytest
from conftest import installed

from drill_sim.cli.main import main
from drill_sim.control.evaluation import LoopSettings, Scenario, run_loop
from drill_sim.control.reference import reference_gains
from drill_sim.core import load_preset

POINT = ["control", "--preset", "base", "--rpm", "60", "--wob-kn", "100", "--duration", "16"]


def test_json_is_one_object_with_a_row_per_law_as_the_loop_computes_it():
    """The installed command, as the README shows it; its z_torque row is what the offline
    loop gives for the same scenario and reference gains (computed here, in this process)."""
    done = subprocess.run([installed("drill_sim"), *POINT, "--laws",
                           "kinematic,stiff_pi,z_torque", "--json"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    rows = {r["name"]: r for r in doc["rows"]}
    assert list(rows) == ["kinematic", "stiff_pi", "z_torque"]
    for row in rows.values():
        assert {"ssi", "stick_fraction", "mean_rop"} <= set(row)
    assert doc["units"]["mean_rop"] == "m/h"
    preset = load_preset("base")
    expected = run_loop(preset, Scenario.steady(60, 100, duration_s=16, window_start_s=8),
                        LoopSettings(law="z_torque",
                                     gains=reference_gains("z_torque", preset, 2900.0)))
    assert rows["z_torque"]["ssi"] == expected.ssi
    assert rows["z_torque"]["mean_rop"] == expected.mean_rop_m_h
    assert rows["kinematic"]["saturation_fraction"] is None        # strict JSON: no NaN


def test_table_csv_and_plot_are_written(tmp_path, capsys):
    out, fig = tmp_path / "t.csv", tmp_path / "t.png"
    assert main([*POINT, "--laws", "stiff_pi", "--motor-torque-min-knm", "0", "--out", str(out),
                 "--plot", str(fig)]) == 0
    text = capsys.readouterr().out
    assert "stiff_pi" in text and "motor torque 0..60 kN m" in text
    with open(out, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert rows[0]["name"] == "stiff_pi"
    assert "mean_rop_m_h [m/h]" in rows[0]
    assert fig.stat().st_size > 10_000


@pytest.mark.parametrize(("argv", "words"), [
    (["--laws", "pid"], "--laws"),
    (["--gain", "z_torque.alpha=nan"], "alpha"),
    (["--gain", "z_torque.beta=1"], "no gain 'beta'"),
    (["--gain", "alpha=1"], "LAW.NAME=VALUE"),
    (["--sample-period", "0"], "--sample-period"),
    (["--motor-torque-min-knm", "5"], "--motor-torque-min-knm"),
    (["--window-start", "20"], "--window-start"),
    (["--out", "x.txt"], ".csv or .json"),
])
def test_bad_options_are_one_line(argv, words, capsys):
    assert main([*POINT, *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert words in err


def test_rpm_without_wob_is_refused(capsys):
    assert main(["control", "--rpm", "60"]) == 2
    assert "--wob-kn" in capsys.readouterr().err


def test_unknown_scenario_set_is_refused(capsys):
    assert main(["control", "--scenarios", "grid,nope"]) == 2
    assert "nope" in capsys.readouterr().err
