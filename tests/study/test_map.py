"""``drill_sim map``: each point is the ``simulate`` run, the output does not depend on how many
workers ran it, an interrupted map resumes without recomputing, a map of other settings is
refused, and bad input ends in one line and status 2 before anything runs."""

from __future__ import annotations

import csv
import json
import subprocess
import sys

import numpy as np
import pytest
from conftest import installed

import drill_sim.cli.map as map_command
from drill_sim.cli.main import main

pytestmark = pytest.mark.offline        # its programs start no node

SMALL = ["--rpm", "40,60,150", "--wob-kn", "80,100", "--duration", "12"]


def rows(path) -> list[dict[str, str]]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """SMALL computed in this process (one worker): the map every other run must equal."""
    out = tmp_path_factory.mktemp("map_ref") / "ref.csv"
    assert main(["map", *SMALL, "--workers", "1", "--out", str(out)]) == 0
    return out


def test_a_point_is_the_simulate_run_bit_for_bit(tmp_path):
    out = tmp_path / "m.csv"
    subprocess.run([installed("drill_sim"), "map", "--preset", "base", *SMALL, "--out",
                    str(out)], check=True, capture_output=True, timeout=300)
    point = next(r for r in rows(out) if r["top_drive_speed_rpm"] == "60.0"
                 and r["wob_kn"] == "100.0")
    proc = subprocess.run([installed("drill_sim"), "simulate", "--preset", "base", "--rpm", "60",
                           "--wob-kn", "100", "--duration", "12", "--json"], check=True,
                          capture_output=True, text=True, timeout=300)
    single = json.loads(proc.stdout)
    assert single["stick_fraction"] > 0           # a stick-slip point: a meaningful comparison
    for column, key in (("stick_fraction", "stick_fraction"), ("ssi", "ssi"),
                        ("bounce_fraction", "bounce_fraction"), ("mean_rop_m_s", "mean_rop"),
                        ("mean_surface_torque_nm", "mean_surface_torque"),
                        ("max_bit_speed_rad_s", "max_bit_speed"), ("mean_wob_n", "mean_wob")):
        assert float(point[column]) == single[key], column


def test_csv_header_units_and_description(reference):
    header = reference.read_text().splitlines()[0].split(",")
    assert header[:3] == ["point", "top_drive_speed_rpm", "wob_kn"]
    for column in ("ssi", "stick_fraction", "bounce_fraction", "speed_drop",
                   "min_bit_speed_rad_s", "max_bit_speed_rad_s", "mean_rop_m_s",
                   "mean_surface_torque_nm", "mse_pa"):
        assert column in header
    description = json.loads(reference.with_suffix(".json").read_text())
    assert description["complete"] and description["points"] == 6
    assert description["settings"]["x"]["values"] == [40.0, 60.0, 150.0]
    assert description["settings"]["package_version"]
    assert description["columns"]["mse_pa"] == "Pa"
    assert [int(r["point"]) for r in rows(reference)] == list(range(6))


def test_two_workers_write_the_same_file_as_one(tmp_path, reference):
    out = tmp_path / "two.csv"
    assert main(["map", *SMALL, "--workers", "2", "--out", str(out)]) == 0
    assert out.read_bytes() == reference.read_bytes()


def test_an_interrupted_map_resumes_without_recomputing(tmp_path, reference, monkeypatch,
                                                        capsys):
    out = tmp_path / "m.csv"
    real = map_command.compute
    asked: list[int] = []

    def interrupted(points, **kw):
        for n, result in enumerate(real(points, **kw)):
            if n == 3:
                raise KeyboardInterrupt
            yield result

    monkeypatch.setattr(map_command, "compute", interrupted)
    with pytest.raises(KeyboardInterrupt):
        map_command.run(_args(SMALL, out))
    assert len(rows(out)) == 3
    assert "3 of 6 points kept" in capsys.readouterr().err
    with open(out, "a") as fh:
        fh.write("garbage,1\n")                           # a damaged line, left out
        fh.write("5,150.0,100.0,0.1")                     # a row torn by a kill: recomputed

    def counting(points, **kw):
        asked.append(len(points))
        yield from real(points, **kw)

    monkeypatch.setattr(map_command, "compute", counting)
    assert main(["map", *SMALL, "--workers", "1", "--out", str(out)]) == 0
    assert asked == [3]
    said = capsys.readouterr().err                         # the discarded lines, named
    assert "3 points kept, 2 damaged line(s) left out" in said, said
    assert "line 5: 2 fields, not" in said and "line 6: cut short" in said, said
    assert out.read_bytes() == reference.read_bytes()
    assert main(["map", *SMALL, "--out", str(out)]) == 0        # done: nothing to compute
    assert asked == [3, 0]
    assert "nothing to compute" in capsys.readouterr().out


def _args(argv: list[str], out) -> object:
    from drill_sim.cli.main import build_parser
    return build_parser().parse_args(["map", *argv, "--workers", "1", "--out", str(out)])


def test_other_settings_are_refused_naming_the_difference(tmp_path, reference, capsys):
    out = tmp_path / "m.csv"
    out.write_bytes(reference.read_bytes())
    out.with_suffix(".json").write_bytes(reference.with_suffix(".json").read_bytes())
    before = out.read_bytes()
    args = [a if a != "12" else "10" for a in SMALL]
    assert main(["map", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"--out {out}" in err and "duration 12.0 there, 10.0 now" in err
    assert err.count("\n") == 1 and out.read_bytes() == before
    assert main(["map", *SMALL, "--preset", "deep", "--out", str(out)]) == 2
    assert "preset base there, deep now" in capsys.readouterr().err
    (tmp_path / "lone.csv").write_text("a,b\n1,2\n")
    assert main(["map", *SMALL, "--out", str(tmp_path / "lone.csv")]) == 2
    assert "missing or unreadable" in capsys.readouterr().err


def test_plot_with_log_axes_and_another_metric(tmp_path, monkeypatch):
    out, png = tmp_path / "m.csv", tmp_path / "m.png"
    import drill_sim.cli.map as map_cli
    drawn = {}
    real = map_cli.plot_map

    def spy(path, x, y, values, stick, **kw):
        drawn.update(values=values, stick=stick, label=kw["metric_label"])
        return real(path, x, y, values, stick, **kw)

    monkeypatch.setattr(map_cli, "plot_map", spy)
    assert main(["map", "--rpm", "30:250:4", "--wob-kn", "80:200:3", "--log", "--duration", "8",
                 "--workers", "1", "--out", str(out), "--plot", str(png), "--metric", "ssi"]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the figure's field is the SSI column of the CSV, point by point, and says so
    assert drawn["label"].startswith("ssi")
    ssi = np.array([float(r["ssi"]) for r in rows(out)]).reshape(4, 3)
    assert np.array_equal(drawn["values"], ssi)
    assert np.array_equal(drawn["stick"], np.array(
        [float(r["stick_fraction"]) > 0 for r in rows(out)]).reshape(4, 3))
    values = [float(r["top_drive_speed_rpm"]) for r in rows(out)][::3]
    assert values[0] == 30.0 and values[-1] == 250.0
    assert values[1] == pytest.approx(30.0 * (250 / 30) ** (1 / 3))       # geometric spacing


def test_groups_mode_sweeps_any_two_quantities(tmp_path):
    out = tmp_path / "g.csv"
    assert main(["map", "--groups", "n=4,psi=13.73,lambda=6.84,beta=0.36", "--w0", "9.6",
                 "--omega0", "1,3", "--beta", "0.5,2", "--duration", "40", "--workers", "1",
                 "--out", str(out)]) == 0
    table = rows(out)
    assert list(table[0])[:3] == ["point", "omega0", "beta"]
    assert [(r["omega0"], r["beta"]) for r in table] == [("1.0", "0.5"), ("1.0", "2.0"),
                                                          ("3.0", "0.5"), ("3.0", "2.0")]
    description = json.loads(out.with_suffix(".json").read_text())
    assert description["settings"]["fixed"] == {"w0": 9.6, "psi": 13.73, "lambda": 6.84}
    assert description["columns"]["mse_rotary"] == "epsilon"
    # each point ran its own beta (the groups' 0.36 for all would give equal rows): at each
    # speed the two betas give different runs
    ssi = {(r["omega0"], r["beta"]): r["ssi"] for r in table}
    assert ssi[("1.0", "0.5")] != ssi[("1.0", "2.0")]
    assert ssi[("3.0", "0.5")] != ssi[("3.0", "2.0")]


@pytest.mark.parametrize("args, fragments", [
    (["--rpm", "20:500:30"], ["--rpm 20:500:30: 500 is out of range", "0 to 400 rpm"]),
    (["--rpm", "20:300"], ["--rpm 20:300", "start:stop:count"]),
    (["--rpm", "20:300:1"], ["count", "2 to 1,000"]),
    (["--rpm", "300:20:5"], ["start is not below stop"]),
    (["--rpm", "0:300:5", "--log"], ["--log", "0 is not positive"]),
    (["--rpm", "40,40"], ["repeated"]),
    (["--wob-kn", "fast"], ["--wob-kn fast", "not a number"]),
    (["--groups", "n=4,psi=13.73,lambda=6.84,beta=0.36", "--w0", "9,10", "--omega0", "1,2",
      "--beta", "0.5,2"], ["--omega0, --w0, --beta", "at most two"]),
    (["--groups", "n=4,psi=13.73,lambda=6.84,beta=0.36", "--w0", "9"], ["--w0 and --omega0"]),
    (["--w0", "9"], ["--w0 goes with --groups"]),
    (["--workers", "0"], ["--workers 0", "1 to 1,024"]),
    (["--workers", "2", "--scheduler", "tcp://localhost:8786"], ["--workers", "--scheduler"]),
    (["--scheduler", "bad address"], ["--scheduler bad address", "not a Dask scheduler address",
                                      "tcp://10.0.0.5:8786"]),   # at once (a 40 s hang before)
    (["--scheduler", "tcp://host"], ["not a Dask scheduler address"]),
    (["--plot", "{tmp}/m.txt"], ["--plot", ".txt", "expected one of"]),
    (["--rpm", "60", "--plot", "{tmp}/m.png"], ["--plot", "at least two values of --rpm"]),
    (["--out", "{tmp}/no/such/m.csv"], ["--out", "does not exist"]),
    (["--wob-kn", "50,100", "--start", "steady"], ["--start steady at --rpm", "--wob-kn 50",
                                                   "no steady drilling"]),
    (["--duration", "1e9"], ["--duration 1e9", "steps"]),
    (["--metric", "colour"], ["--metric", "invalid choice"]),
])
def test_bad_input_is_one_line_before_anything_runs(tmp_path, capsys, args, fragments):
    model = [] if "--groups" in args else ["--rpm", "40,60", "--wob-kn", "80,100"]
    argv = ["map", *model, "--duration", "1", "--out", str(tmp_path / "m.csv")]
    argv += [a.replace("{tmp}", str(tmp_path)) for a in args]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("drill_sim: error: ") and err.count("\n") == 1, err
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    assert not (tmp_path / "m.csv").exists()


def test_scheduler_without_dask_says_how_to_install(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)      # import distributed fails
    assert main(["map", *SMALL, "--scheduler", "tcp://127.0.0.1:1", "--out",
                 str(tmp_path / "m.csv")]) == 2
    err = capsys.readouterr().err
    assert "--scheduler tcp://127.0.0.1:1" in err and 'pip install "dask[distributed]"' in err
    assert err.count("\n") == 1 and not (tmp_path / "m.csv").exists()
