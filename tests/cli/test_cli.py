"""The ``drill_sim`` console script, run as a user runs it: the installed entry point."""

from __future__ import annotations

import csv
import json
import re
import subprocess

import pytest
from conftest import installed


def run(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    proc = subprocess.run([installed("drill_sim"), *args], capture_output=True, text=True,
                          timeout=300)
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


@pytest.mark.offline
def test_simulate_si_writes_csv_plot_and_json(tmp_path):
    out, png = tmp_path / "run.csv", tmp_path / "run.png"
    proc = run("simulate", "--preset", "base", "--rpm", "60", "--wob-kn", "100", "--duration",
               "60", "--out", str(out), "--plot", str(png), "--output-interval", "0.05", "--json")
    summary = json.loads(proc.stdout)
    for key in ("ssi", "stick_fraction", "bounce_fraction", "mean_bit_speed", "mean_wob",
                "mean_tob", "mean_surface_torque", "mean_rop"):
        assert isinstance(summary[key], float), key
    assert summary["mean_wob"] == pytest.approx(100e3, rel=0.01)        # N
    assert summary["mean_bit_speed"] == pytest.approx(6.2832, rel=0.05)  # rad/s
    with open(out, newline="") as fh:
        rows = list(csv.reader(fh))
    for column in ("time_s", "bit_speed_rad_s", "rop_m_s", "wob_n", "tob_nm", "surface_torque_nm",
                   "depth_of_cut_m", "stuck", "off_bottom"):
        assert column in rows[0]
    assert len(rows) == 1 + 1200
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.offline
def test_simulate_groups_mode_is_dimensionless(tmp_path):
    out = tmp_path / "g.csv"
    proc = run("simulate", "--groups", "n=4,psi=13.73,lambda=6.84,beta=0.36", "--w0", "9.6",
               "--omega0", "1.32", "--duration", "100", "--out", str(out), "--json")
    summary = json.loads(proc.stdout)
    assert summary["mean_wob"] == pytest.approx(9.6, rel=0.01)
    assert summary["stick_fraction"] > 0.2
    header = out.read_text().splitlines()[0].split(",")
    assert {"tau", "omega", "v", "w", "t", "ts", "delta_n", "stuck", "off_bottom"} <= set(header)


@pytest.mark.offline
def test_text_summary_has_units():
    proc = run("simulate", "--duration", "5")
    assert "rpm" in proc.stdout and "kN" in proc.stdout and "stick fraction" in proc.stdout


@pytest.mark.offline
def test_stability_json():
    proc = run("stability", "--preset", "base", "--json")
    out = json.loads(proc.stdout)
    assert out["complete"] and not out["stable"]
    re, im = out["roots"][0]
    assert re == pytest.approx(0.749, abs=0.01) and abs(im) == pytest.approx(8.45, abs=0.05)
    assert out["si"]["wob_n"] == pytest.approx(1e5)


@pytest.mark.offline
def test_stability_without_steady_drilling_says_so():
    proc = run("stability", "--wob-kn", "20", "--json")
    out = json.loads(proc.stdout)
    assert out["steady_drilling"] is False and "no steady drilling" in out["reason"]


@pytest.mark.offline
@pytest.mark.parametrize("args, fragment", [
    (("simulate", "--rpm", "nan"), "--rpm"),
    (("simulate", "--rpm", "-10"), "--rpm"),
    (("simulate", "--rpm", "fast"), "--rpm"),
    (("simulate", "--wob-kn", "1e6"), "submerged weight"),
    (("simulate", "--hook-load-kn", "-1"), "--hook-load-kn"),
    (("simulate", "--duration", "0"), "--duration"),
    (("simulate", "--dt", "inf"), "--dt"),
    (("simulate", "--dt", "1"), "dt"),
    (("simulate", "--preset", "nowhere"), "preset"),
    (("simulate", "--groups", "n=4,psi=1"), "--groups"),
    (("simulate", "--groups", "n=4,psi=1,lambda=1,beta=1"), "--w0"),
    (("simulate", "--groups", "n=0,psi=1,lambda=1,beta=1", "--w0", "1", "--omega0", "1"),
     "blade count"),
    (("simulate", "--w0", "3"), "--groups"),
    (("simulate", "--out", "/no/such/dir/x.csv"), "does not exist"),
    (("simulate", "--start", "steady", "--wob-kn", "10"), "no steady drilling"),
    (("stability", "--re-min", "1"), "--re-min"),
    (("frobnicate",), "invalid choice"),
])
def test_bad_arguments_exit_2_with_one_clear_line(args, fragment):
    proc = run(*args, check=False)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr


def test_main_job_runs_the_node_playing_its_scenario_and_writes_summary_and_plot(tmp_path):
    from rosutil import isolate
    isolate()
    png = tmp_path / "run.png"
    proc = subprocess.run([installed("drill_sim"), "run", "--scenario", "step_test",
                           "--duration", "12", "--plot", str(png)], capture_output=True,
                          text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "hole drilled" in proc.stdout and "stick fraction" in proc.stdout
    assert "rpm" in proc.stdout and "WOB" in proc.stdout          # the live status lines
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # recorded by default; a real-time session with its scenario's commands re-runs exactly
    (bag,) = tmp_path.glob("drill_sim_session_*")
    assert f"session recorded to {bag.name}" in proc.stdout
    # the summary counts what the node published: the samples of its bag
    from drill_sim.bag import reader
    samples = int(re.search(r"(\d+) samples", proc.stdout).group(1))
    assert samples == reader.info(bag).topics["/drill_sim/joint_states"].count
    assert re.search(r"\| (steady|torsional oscillation|stick-slip) ", proc.stdout)
    resim = run("bag", "resim", str(bag), "--json", check=False)
    assert resim.returncode == 0, resim.stdout + resim.stderr
    r = json.loads(resim.stdout)
    # step_test: the start's speed and load, the steps at 10 s (speed) and 30 s (load, past
    # the 12 s run), each recorded once, on the tick of its time
    assert r["exact"] and r["mode"] == "real-time" and r["commands"] == 3


@pytest.mark.untimed("a refusal: the main job ends at once")
def test_main_job_bad_arguments(tmp_path):
    proc = run("run", "--scenario", "nowhere", check=False)
    assert proc.returncode == 2 and "scenario" in proc.stderr and "Traceback" not in proc.stderr
    (tmp_path / "taken").mkdir()
    for bag, expected in ((tmp_path / "taken", "it exists already"),
                          (tmp_path / "no" / "such", "does not exist")):
        proc = run("run", "--record", str(bag), check=False)
        assert proc.returncode == 2 and expected in proc.stderr, proc.stderr
        assert "Traceback" not in proc.stderr
    assert list((tmp_path / "taken").iterdir()) == []          # nothing written into it


def test_main_job_refuses_to_mix_with_a_rig_already_running(tmp_path):
    """A rig of the same name already on the domain: the session would mix both rigs'
    samples and drive both, so run stops, naming it, with status 1."""
    from rosutil import NodeProcess, isolate
    isolate()
    with NodeProcess("drill_sim_node") as other:
        assert other.proc.stdout.readline()                # it is up
        proc = subprocess.run([installed("drill_sim"), "run", "--duration", "30", "--no-record"],
                              capture_output=True, text=True, timeout=120, cwd=tmp_path)
        assert other.proc.poll() is None                    # left alone
    assert proc.returncode == 1, proc.stdout + proc.stderr
    # named, or, under load, found before its node's name came (either way it is refused)
    assert re.search(r"another rig publishes on /drill_sim/joint_states \((/drill_sim|\(a node "
                     r"not yet named\))\)", proc.stderr) and "Traceback" not in proc.stderr, \
        proc.stderr
    # (mostly refused before its rig starts; under load discovery may take ~3 s, and the
    # session it had started is then stopped: the same refusal)
    # one that comes during the session stops it too
    session = subprocess.Popen([installed("drill_sim"), "run", "--duration", "60",
                                "--no-record"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    try:
        assert "rpm" in session.stdout.readline()          # the first status line
        with NodeProcess("drill_sim_node"):
            code = session.wait(timeout=60)
    finally:
        session.kill()
    err = session.stderr.read()
    assert code == 1 and "another rig publishes on /drill_sim/joint_states (" in err, err


@pytest.mark.untimed("a refusal: the main job ends at once")
@pytest.mark.parametrize("param, fragment", [
    ("initial_state:=sideways", "initial_state = 'sideways'"),
    ("record_split_size_bytes:=1", "1 MiB at least"),
    ("max_speed:=true", "needs publish_clock"),
])
def test_main_job_passes_on_a_bad_node_parameter_in_one_line(param, fragment):
    from rosutil import isolate
    isolate()
    proc = subprocess.run([installed("drill_sim"), "run", "--duration", "20", "--no-record",
                           "--ros-args", "-p", param], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr + proc.stdout


@pytest.mark.offline
def test_stability_shows_the_rig_key_figures():
    text = run("stability", "--preset", "base").stdout
    assert "rig: W_s 338 kN, t* 0.210 s, torsional 0.756 Hz (period 1.32 s), axial 5.61 Hz" \
        in text
    figures = json.loads(run("stability", "--preset", "deep", "--json").stdout)["si"]["figures"]
    assert figures["t_star_s"] == pytest.approx(0.364, rel=0.01)
    assert figures["beta"] == pytest.approx(0.36)
