"""``drill_sim control`` as a user types it: one JSON object with a row per law, the table it
writes, its figure, and one-line refusals of bad options."""

from __future__ import annotations

import csv
import json
import subprocess

import pytest
from conftest import installed

from drill_sim.cli.main import main
from drill_sim.control.closed_loop import run_loop
from drill_sim.control.evaluation import LoopSettings, Scenario
from drill_sim.control.reference import reference_gains
from drill_sim.core import load_preset
from drill_sim.core.effort import EFFORT_KEYS

POINT = ["control", "--preset", "base", "--rpm", "60", "--wob-kn", "100", "--duration", "16"]


@pytest.mark.offline                # its program starts no node
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
    assert doc["gains"]["z_torque"] == reference_gains("z_torque", preset, 2900.0)  # what ran
    assert doc["gains"]["kinematic"] == {}


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


def test_a_weight_the_bit_cannot_drill_at_is_one_line_naming_the_least(capsys):
    """Below λ (the wear flats' friction, in SI λ F*) there is no steady drilling to start
    from: one line that names the scenario and the least weight, not a traceback; just above
    it the run goes."""
    from drill_sim.core import load_preset
    rig = load_preset("base").rig
    least_kn = rig.groups.lam * rig.scales.force_n / 1e3
    below = ["control", "--preset", "base", "--rpm", "60", "--laws", "kinematic",
             "--duration", "2", "--wob-kn"]
    assert main([*below, f"{0.99 * least_kn:.6g}"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "its steady start: no steady drilling" in err
    assert f"above {least_kn:.4g} kN" in err
    assert main([*below, f"{1.01 * least_kn:.6g}", "--json"]) == 0


def test_rpm_without_wob_is_refused(capsys):
    assert main(["control", "--rpm", "60"]) == 2
    assert "--wob-kn" in capsys.readouterr().err


def test_unknown_scenario_set_is_refused(capsys):
    assert main(["control", "--scenarios", "grid,nope"]) == 2
    assert "nope" in capsys.readouterr().err


def test_scenarios_with_one_steady_point_is_refused_not_ignored(capsys):
    """--scenarios and --rpm/--wob-kn contradict each other: one line, exit 2 (it used to
    run the steady point and drop --scenarios without a word)."""
    assert main(["control", "--rpm", "60", "--wob-kn", "100", "--scenarios", "bogus"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "--scenarios bogus with --rpm/--wob-kn" in err


def test_main_job_switches_the_scenarios_controller_on_and_compares(tmp_path):
    """A scenario with a controller section: the rig starts on its own speed loop, the driver
    switches drill_sim_controller on at on_at_s, the summary compares before and after; here
    on the distributed string (``--string-model``: the rig's model, which the node says, and
    the controller's tuning for it)."""
    from rosutil import isolate
    isolate()
    scenario = tmp_path / "on.yaml"
    scenario.write_text("description: steady, then Z-Torque\ninitial_state: steady\n"
                        "duration_s: 7.0\npoints:\n  - {at_s: 0.0, rpm: 60.0, wob_kn: 100.0}\n"
                        "controller: {law: z_torque, on_at_s: 2.5}\n")
    proc = subprocess.run([installed("drill_sim"), "run", "--scenario", str(scenario),
                           "--record", str(tmp_path / "bag"), "--plot", str(tmp_path / "on.png"),
                           "--string-model", "distributed"],
                          capture_output=True, text=True, timeout=180, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    # the drive's effort from the bag's motor torque, and the settling after the switch, in
    # the summary as ``bag metrics`` gives them for the same bag
    metrics = json.loads(subprocess.run(
        [installed("drill_sim"), "bag", "metrics", str(tmp_path / "bag"), "--json"],
        capture_output=True, text=True, timeout=60, check=True).stdout)
    assert set(EFFORT_KEYS) <= set(metrics)
    assert (f"drive effort (whole run): motor torque rms about its mean "
            f"{metrics['motor_torque_rms_nm'] / 1e3:.2f} kN m") in proc.stdout, proc.stdout
    assert metrics["time_at_torque_limit_fraction"] is not None     # the drive has limits
    assert "settling after 2.5 s: " in proc.stdout
    assert "rig 'base' ready: distributed string" in proc.stderr
    assert "on preset 'base' (distributed string)" in proc.stdout
    assert "controller z_torque switched on at" in proc.stderr + proc.stdout   # the driver
    assert "controller z_torque switched on at 2.5 s: SSI" in proc.stdout       # the summary
    assert "stick-slip: no stick-slip before the switch" in proc.stdout
    # stopped in order, the controller hands the drive back while the rig is still there
    assert "top drive is back on its speed loop" in proc.stderr, proc.stderr
    assert "[ERROR]" not in proc.stderr, proc.stderr


@pytest.mark.offline                # its program starts no node
def test_the_start_perturbation_is_one_option_and_an_offline_run_writes_an_exact_bag(
        tmp_path, capsys):
    """``--perturbation`` sets the steady start's perturbation (today's 1e-3 by default; the
    rig node's ``initial_perturbation`` is the same start), and ``--record`` writes each row
    as the node would record it, which ``drill_sim bag resim`` re-runs bit for bit."""
    point = ["control", "--rpm", "60", "--wob-kn", "100", "--duration", "4", "--laws",
             "z_torque", "--json"]
    printed = {}
    for value in ("0", "0.002", None):
        extra = [] if value is None else ["--perturbation", value]
        record = ["--record", str(tmp_path / "bags")] if value is None else []
        assert main([*point, *extra, *record]) == 0
        printed[value] = json.loads(capsys.readouterr().out)["rows"][0]["ssi"]
    preset = load_preset("base")
    gains = reference_gains("z_torque", preset, 2900.0)
    scenario = Scenario.steady(60, 100, duration_s=4, window_start_s=2)
    for value, p in (("0", 0.0), ("0.002", 2e-3), (None, 1e-3)):
        offline = run_loop(preset, scenario, LoopSettings(law="z_torque", gains=gains,
                                                          perturbation=p))
        assert printed[value] == offline.ssi, value
    assert printed["0"] < 1e-6 < min(printed[None], printed["0.002"])   # steady unless perturbed
    bag = tmp_path / "bags" / "60rpm_100kN-z_torque"
    done = subprocess.run([installed("drill_sim"), "bag", "resim", str(bag), "--json"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert result["exact"] is True and result["samples"] == 4001
    assert result["commands"] >= 4000 and result["refused"] == 0


def test_the_main_jobs_controller_is_tuned_for_the_rigs_string_model():
    """``drill_sim run``'s controller gets the reference gains of the string the rig runs:
    the distributed string's f1 (0.57 Hz on base) is not the lumped one's (0.76 Hz)."""
    from drill_sim.cli.run import controller_command
    from drill_sim.control.reference import reference_gains
    from drill_sim.core import load_preset
    preset = load_preset("base")
    j_td = preset.top_drive.top_drive_inertia_kg_m2
    for model in ("lumped", "distributed"):
        cmd = controller_command(preset, "soft_speed", model)
        given = {a.split(":=")[0]: a.split(":=")[1] for a in cmd if ":=" in a}
        for name, value in reference_gains("soft_speed", preset, j_td,
                                           string_model=model).items():
            assert float(given[f"soft_speed.{name}"]) == value, (model, name)
    lumped = controller_command(preset, "soft_speed", "lumped")
    assert lumped != controller_command(preset, "soft_speed", "distributed")


def test_a_users_controller_row_is_not_shown_with_the_reference_gains():
    """``--ros --ros-controller COMMAND`` scores the user's own controller: the document names
    its command and shows no reference gains for it (they are not what ran)."""
    import argparse

    from drill_sim.cli.control import _document
    preset = load_preset("base")
    settings = [LoopSettings(law="z_torque",
                             gains=reference_gains("z_torque", preset, 2900.0))]
    args = argparse.Namespace(sensor_profile="ideal", ros=True, sensor_seed=0,
                              string_model="lumped", published_gains=False,
                              ros_controller="python3 my_controller.py")
    doc = _document(args, "base", preset.top_drive, 1e-3, [], settings)
    assert doc["gains"] == {"user": {}}
    assert doc["controller_command"] == "python3 my_controller.py"
    args.ros_controller = None
    doc = _document(args, "base", preset.top_drive, 1e-3, [], settings)
    assert doc["gains"]["z_torque"]["kp_nm_s_rad"] == pytest.approx(
        settings[0].gains["kp_nm_s_rad"])
    assert doc["controller_command"] is None
