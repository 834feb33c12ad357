"""The top drive's options of ``drill_sim simulate`` and ``drill_sim map``: the drive's speed
loop and torque command reach the run, its columns and summary carry units, a map point is the
simulate run with the same options, and options that do nothing or do not fit are one line."""

from __future__ import annotations

import csv
import json
import math

import pytest

from drill_sim.cli.main import main
from drill_sim.core import load_preset

SPEED = ["--preset", "base", "--rpm", "60", "--wob-kn", "100", "--top-drive-mode", "speed"]


def _rows(path) -> list[dict[str, str]]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _json(capsys, argv: list[str]) -> dict:
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_speed_mode_holds_the_set_point_and_writes_the_drive_columns(tmp_path, capsys):
    out = tmp_path / "speed.csv"
    s = _json(capsys, ["simulate", *SPEED, "--duration", "40", "--out", str(out), "--json"])
    assert s["top_drive"]["top_drive_mode"] == "speed"
    assert s["top_drive"]["drive_ki_nm_rad"] == pytest.approx(5 * 2900.0)
    assert s["units"]["mean_top_drive_speed"] == "rad/s"
    assert s["units"]["mean_motor_torque"] == "N m"
    # the integral holds the mean speed on the set-point: 2e-4 off over the window, where P
    # alone (K_i 0) leaves it 3.8e-3 low even with the steady start's torque preloaded
    assert s["mean_top_drive_speed"] == pytest.approx(2 * math.pi, rel=1.2e-3)
    assert s["mean_motor_torque"] == pytest.approx(s["mean_surface_torque"], rel=0.02)
    assert s["stick_fraction"] > 0.2
    rows = _rows(out)
    assert {"top_drive_speed_rad_s", "top_drive_speed_setpoint_rad_s", "motor_torque_nm"} \
        <= set(rows[0])
    setpoints = [float(r["top_drive_speed_setpoint_rad_s"]) for r in rows]
    assert setpoints == pytest.approx([2 * math.pi] * len(rows), rel=1e-8)
    speeds = [float(r["top_drive_speed_rad_s"]) for r in rows]
    assert max(speeds) > min(speeds)                  # the top drive's own speed, not the command


def test_torque_mode_off_bottom_accelerates_under_the_command(tmp_path, capsys):
    out = tmp_path / "torque.csv"
    s = _json(capsys, ["simulate", "--preset", "base", "--top-drive-mode", "torque",
                       "--motor-torque-knm", "2", "--start", "rest", "--gap", "0.01",
                       "--wob-kn", "0", "--duration", "10", "--out", str(out), "--json"])
    assert s["motor_torque_command"] == 2e3 and s["bounce_fraction"] == pytest.approx(1.0)
    rows = _rows(out)
    assert {float(r["motor_torque_nm"]) for r in rows} == {2e3}
    # the motor's torque goes into the drive's and the BHA's momentum and nowhere else (off
    # bottom, no damping): J_TD w_TD + I w_bit = T t, whatever the two-inertia mode rings
    i_bha = load_preset("base").rig.bha_inertia_kg_m2
    for r in rows[::50]:
        momentum = 2900.0 * float(r["top_drive_speed_rad_s"]) + i_bha * float(r["bit_speed_rad_s"])
        assert momentum == pytest.approx(2e3 * float(r["time_s"]), rel=1e-6, abs=1e-6)


def test_a_map_point_is_the_simulate_run_with_the_same_drive(tmp_path, capsys):
    drive = ["--top-drive-mode", "speed", "--motor-torque-max-knm", "8", "--drive-lag-s", "0.01"]
    out = tmp_path / "m.csv"
    assert main(["map", "--preset", "base", "--rpm", "60,80", "--wob-kn", "100", *drive,
                 "--duration", "12", "--workers", "1", "--out", str(out)]) == 0
    capsys.readouterr()
    point = next(r for r in _rows(out) if r["top_drive_speed_rpm"] == "60.0")
    single = _json(capsys, ["simulate", *SPEED, *drive, "--duration", "12", "--json"])
    for column, key in (("stick_fraction", "stick_fraction"), ("ssi", "ssi"),
                        ("mean_surface_torque_nm", "mean_surface_torque")):
        assert float(point[column]) == single[key], column
    plain = _json(capsys, ["simulate", *SPEED[:-2], "--duration", "12", "--json"])
    assert plain["ssi"] != single["ssi"]             # the drive did reach the run
    settings = json.loads(out.with_suffix(".json").read_text())["settings"]
    assert settings["top_drive_mode"] == "speed" and settings["motor_torque_max_knm"] == 8.0


@pytest.mark.parametrize("args, fragments", [
    (["--drive-kp", "100"], ["--drive-kp", "kinematic", "--top-drive-mode speed"]),
    (["--top-drive-inertia", "100"], ["--top-drive-inertia", "speed or torque"]),
    (["--top-drive-mode", "speed", "--motor-torque-knm", "3"], ["--motor-torque-knm", "torque"]),
    (["--top-drive-mode", "torque", "--drive-ki", "3"], ["--drive-ki", "speed"]),
    (["--groups", "n=4,psi=13.73,lambda=6.84,beta=0.36", "--w0", "9.6", "--omega0", "1.3",
      "--top-drive-mode", "speed"], ["--top-drive-mode", "SI"]),
    (["--top-drive-mode", "speed", "--motor-torque-min-knm", "0", "--motor-torque-max-knm", "0"],
     ["--motor-torque-min-knm 0", "below"]),
    (["--top-drive-mode", "speed", "--motor-torque-max-knm", "3"],
     ["--start steady", "kN m", "--start rest"]),
    (["--top-drive-mode", "torque", "--top-drive-inertia", "1e9"], ["--top-drive-inertia 1e9"]),
    (["--top-drive-mode", "speed", "--top-drive-inertia", "1", "--dt", "0.005"],
     ["--dt", "--top-drive-inertia"]),
    (["--top-drive-mode", "torque", "--motor-torque-knm", "nan"], ["--motor-torque-knm nan"]),
])
def test_bad_top_drive_options_are_one_line(capsys, args, fragments):
    assert main(["simulate", "--duration", "1", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    for fragment in fragments:
        assert fragment in err[0], err[0]
