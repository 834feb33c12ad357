"""``--string-model``: the distributed string from the command line."""

from __future__ import annotations

import json
import math
import subprocess

import pytest
from conftest import installed

pytestmark = pytest.mark.offline        # its programs start no node


def run(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    proc = subprocess.run([installed("drill_sim"), *args], capture_output=True, text=True,
                          timeout=300)
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


def test_simulate_distributed_differs_from_lumped_and_keeps_the_mean_speed():
    """On base at 60 rpm / 100 kN the pipe's inertia and damping change the stick-slip (stick
    fraction 0.18 against 0.43 over the last 120 s of 240; it grows slowly: 0.05 over the
    last 60 s of 120), while <Omega> = Omega0 holds (1 %)."""
    common = ("simulate", "--preset", "base", "--rpm", "60", "--wob-kn", "100", "--duration",
              "240", "--json")
    lumped = json.loads(run(*common).stdout)
    string = json.loads(run(*common, "--string-model", "distributed").stdout)
    assert lumped["string_model"] == "lumped" and string["string_model"] == "distributed"
    assert abs(string["stick_fraction"] - lumped["stick_fraction"]) > 0.1
    assert string["mean_bit_speed"] == pytest.approx(string["top_drive_speed"], rel=1e-2)
    assert string["mean_wob"] == pytest.approx(100e3, rel=1e-2)


def test_simulate_distributed_from_rest():
    proc = run("simulate", "--string-model", "distributed", "--start", "rest", "--gap", "1",
               "--wob-kn", "0", "--duration", "5", "--json")
    out = json.loads(proc.stdout)
    assert out["start"] == "rest" and out["stick_fraction"] == 0.0


def test_distributed_in_groups_mode_is_refused():
    proc = run("simulate", "--groups", "n=4,psi=13.73,lambda=6.84,beta=0.36", "--w0", "9.6",
               "--omega0", "1.32", "--string-model", "distributed", check=False)
    assert proc.returncode == 2
    (line,) = proc.stderr.strip().splitlines()
    assert "--string-model distributed with --groups" in line and "geometry" in line


def test_map_passes_the_string_model_to_every_point(tmp_path):
    out = tmp_path / "m.csv"
    args = ("map", "--rpm", "60,120", "--wob-kn", "100", "--duration", "20", "--workers", "1",
            "--out")
    run(*args, str(out), "--string-model", "distributed")
    run(*args, str(tmp_path / "l.csv"))
    description = json.loads(out.with_suffix(".json").read_text())
    assert "distributed" in json.dumps(description)
    assert out.read_text() != (tmp_path / "l.csv").read_text()


def test_stability_distributed_roots_check_and_frequencies():
    """The rightmost roots of Delta_d, complete by the argument principle on the box (whose
    height bounds the search, as the text says), and the off-bottom frequencies of base."""
    out = json.loads(run("stability", "--string-model", "distributed", "--json").stdout)
    assert out["string_model"] == "distributed" and out["complete"] and not out["stable"]
    assert out["roots_found"] == out["roots_counted"] > 0
    re, _im = out["roots"][0]
    assert re == max(r[0] for r in out["roots"]) > 0
    assert "argument principle" in out["completeness"] and "not searched" in out["completeness"]
    assert out["torsional_frequencies_hz"] == pytest.approx([0.555, 1.830, 3.271], abs=2e-3)
    assert out["axial_frequencies_hz"] == pytest.approx([1.858, 4.078], abs=2e-3)
    text = run("stability", "--string-model", "distributed").stdout
    assert "argument principle" in text and "not searched" in text
    assert "torsional 0.555, 1.830, 3.271 Hz; axial 1.858, 4.078 Hz" in text
    lumped = json.loads(run("stability", "--json").stdout)
    assert "string_model" not in lumped and lumped["complete"]
    assert out["wall_friction_left_out"] is False and "left out" not in text


def test_stability_on_a_well_that_rubs_says_the_walls_friction_is_left_out():
    """field_a rubs along its built section: its roots and modes are the linear string's, and
    the text and the JSON say the set-valued wall is not in them (a user comparing them with a
    simulation of the same point sees why they differ)."""
    out = json.loads(run("stability", "--preset", "field_a", "--string-model", "distributed",
                         "--json").stdout)
    assert out["wall_friction_left_out"] is True
    text = run("stability", "--preset", "field_a", "--string-model", "distributed").stdout
    assert "friction along the string is left out of these roots and modes" in text


def test_stability_distributed_reports_the_damped_modes_with_the_drive_at_the_top():
    """``modes``: five torsional then five axial, lowest first, each with its damped frequency
    near the undamped one (the preset's damping is light) and a damping ratio >= 2 %; the
    drive's PI at the top damps the first torsional mode more than a held top and leaves the
    axial ones alone; the text says the same; a drive option without the distributed string
    is refused."""
    held = json.loads(run("stability", "--string-model", "distributed", "--json").stdout)
    pi = json.loads(run("stability", "--string-model", "distributed", "--json",
                        "--top-drive-mode", "speed").stdout)
    for out in (held, pi):
        assert out["modes_complete"]
        assert [m["kind"] for m in out["modes"]] == ["torsional"] * 5 + ["axial"] * 5
        for kind in ("torsional", "axial"):
            freqs = [m["frequency_hz"] for m in out["modes"] if m["kind"] == kind]
            assert freqs == sorted(freqs)
        assert min(m["damping_ratio"] for m in out["modes"]) >= 0.02
    assert "top drive kinematic" in held["modes_boundary"]
    assert "top drive speed" in pi["modes_boundary"]
    tors = [m["frequency_hz"] for m in held["modes"][:3]]
    assert tors == pytest.approx(held["torsional_frequencies_hz"], rel=2e-3)
    assert pi["modes"][0]["damping_ratio"] > 1.1 * held["modes"][0]["damping_ratio"]
    assert pi["modes"][5:] == held["modes"][5:]
    text = run("stability", "--string-model", "distributed").stdout
    assert "damped modes off bottom" in text and "torsional 0.555 / 4.87" in text
    refused = run("stability", "--top-drive-mode", "speed", check=False)
    assert refused.returncode == 2 and "--string-model distributed" in refused.stderr


def test_simulate_distributed_with_the_top_drive_in_the_loop():
    """--string-model distributed with --top-drive-mode speed and torque: the speed PI keeps
    the mean top-drive speed at the command (1 %); a held motor torque off bottom spins the
    string up (the mean motor torque is the command)."""
    common = ("simulate", "--preset", "base", "--string-model", "distributed", "--json")
    speed = json.loads(run(*common, "--rpm", "60", "--wob-kn", "100", "--duration", "60",
                           "--top-drive-mode", "speed").stdout)
    assert speed["string_model"] == "distributed"
    assert speed["mean_top_drive_speed"] == pytest.approx(speed["top_drive_speed"], rel=1e-2)
    torque = json.loads(run(*common, "--start", "rest", "--gap", "1", "--wob-kn", "0",
                            "--duration", "5", "--top-drive-mode", "torque",
                            "--motor-torque-knm", "5").stdout)
    assert torque["mean_motor_torque"] == pytest.approx(5e3, rel=1e-9)
    assert torque["mean_top_drive_speed"] > 0.0


def test_stability_with_a_law_at_the_top_gives_the_closed_loop_roots():
    """``--law``: the law's reference gains for that sample period and the string (passive up
    to the fifth mode) and the sample period in the JSON, the boundary named, each mode's
    growth rate Re s [1/s] = −ζ ω; Z-Torque's first mode far better damped than the drive with
    its motor torque held; ``--law`` and ``--sample-period`` refused where they do nothing."""
    from drill_sim.control.reference import reference_gains
    from drill_sim.core import load_preset
    held = json.loads(run("stability", "--string-model", "distributed", "--json",
                          "--top-drive-mode", "torque").stdout)
    for law in ("soft_speed", "z_torque"):
        out = json.loads(run("stability", "--string-model", "distributed", "--json", "--law",
                             law, "--sample-period", "0.01").stdout)
        assert (out["law"], out["sample_period_s"]) == (law, 0.01)
        assert out["law_gains"] == pytest.approx(reference_gains(
            law, load_preset("base"), 2900.0, string_model="distributed", sample_period_s=0.01))
        assert f"law {law}" in out["modes_boundary"] and out["modes_complete"]
        for m in out["modes"]:
            omega = 2 * math.pi * m["frequency_hz"] / math.sqrt(1.0 - m["damping_ratio"] ** 2)
            assert m["growth_rate_per_s"] == pytest.approx(-m["damping_ratio"] * omega,
                                                           rel=1e-6)
    assert out["modes"][0]["damping_ratio"] > 5 * held["modes"][0]["damping_ratio"]
    # on bottom: the closed loop keeps the bit's own rightmost (regenerative) root and moves
    # the string's first mode (0.57 Hz with the top held) to more damping
    closed = out["closed_loop_on_bottom"]
    assert closed["complete"] and not closed["stable"]
    bit_held, bit_closed = complex(*out["roots"][0]), complex(*closed["roots"][0])
    assert abs(bit_closed - bit_held) < 1e-3 * abs(bit_held)
    hz = 1.0 / (2.0 * math.pi * out["t_star_s"])

    def first_mode(roots):
        return min((complex(*r) for r in roots if 0.3 < r[1] * hz < 0.8), default=None,
                   key=lambda r: -r.real)
    assert first_mode(out["roots"]).real < 0.0
    moved = first_mode(closed["roots"])
    assert moved is None or moved.real < 1.2 * first_mode(out["roots"]).real
    light = json.loads(run("stability", "--string-model", "distributed", "--json", "--law",
                           "z_torque", "--top-drive-inertia", "500").stdout)
    assert "inertia 500 kg m^2" in light["modes_boundary"]
    for args, words in ((("--law", "z_torque"), "--law"),
                        (("--string-model", "distributed", "--sample-period", "0.01"),
                         "--sample-period"),
                        (("--string-model", "distributed", "--law", "z_torque", "--drive-kp",
                          "1000"), "--drive-kp with --law")):
        refused = run("stability", *args, check=False)
        assert refused.returncode == 2 and words in refused.stderr
