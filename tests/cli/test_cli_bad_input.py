"""Bad input to every command line ends in one clear line on stderr and exit status 2: no
traceback, no NaN in the output, no unbounded work. Run as a user runs them, through the
installed entry points, each in a subprocess capped in memory and time."""

from __future__ import annotations

import json
import re
import resource
import subprocess
from pathlib import Path

import pytest
from conftest import installed

from drill_sim.cli.checks import finite_or_none, join_negative_values, json_line
from drill_sim.core import ParameterError, load_preset
from drill_sim.session.scenario import load_scenario

UNTIMED = pytest.mark.untimed("a refusal: the program ends at once, within a 120 s timeout")

MEMORY_CAP = 3 << 30       # bytes of address space per command: a regression fails, not the host
GROUPS = "n=4,psi=13.73,lambda=6.84,beta=0.36"


def _cap_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP, MEMORY_CAP))


def run(program: str, *args: str, cwd: Path | None = None,
        timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run([installed(program), *args], capture_output=True, text=True,
                          timeout=timeout, cwd=cwd, preexec_fn=_cap_memory)


def _strict(text: str) -> object:
    """JSON as RFC 8259 has it: NaN and Infinity are refused."""
    def refuse(token: str) -> None:
        raise ValueError(f"{token} is not JSON")
    return json.loads(text, parse_constant=refuse)


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, Path]:
    """A binary 'YAML' file and a small bag."""
    from rclpy.serialization import serialize_message
    from std_msgs.msg import Float64

    from drill_sim.bag.writer import BagWriter

    root = tmp_path_factory.mktemp("bad_input")
    binary = root / "binary.yaml"
    binary.write_bytes(b"\xff\xfe\x00\x01 not text \x80\x81")
    bag = root / "bag"
    with BagWriter(bag) as w:
        w.add_topic("/bad_input/value", "std_msgs/msg/Float64")
        for i in range(20):
            w.write("/bad_input/value", serialize_message(Float64(data=float(i))),
                    1_700_000_000_000_000_000 + i * 10_000_000)
    return {"root": root, "binary": binary, "bag": bag}


# program, arguments ({root}, {binary}, {bag} are filled in), fragments the line must hold
CASES = [
    # a binary preset or scenario file
    ("drill_sim", ["simulate", "--preset", "{binary}"], ["{binary}", "not a text file",
                                                         "expected a YAML text file"]),
    ("drill_sim", ["stability", "--preset", "{binary}"], ["{binary}", "not a text file"]),
    ("drill_sim", ["run", "--scenario", "{binary}", "--duration", "1", "--no-record"],
     ["{binary}", "not a text file"]),
    # plot formats, checked before the run
    ("drill_sim", ["simulate", "--duration", "1", "--plot", "{root}/x.txt"],
     ["--plot {root}/x.txt", ".txt", "expected one of", ".png", ".pdf"]),
    ("drill_sim", ["simulate", "--duration", "1", "--plot", "{root}/figure"],
     ["--plot {root}/figure", "no file extension", "expected one of", ".png"]),
    ("drill_sim", ["run", "--duration", "1", "--no-record", "--plot", "{root}/x.txt"],
     ["--plot {root}/x.txt", "expected one of"]),
    # numbers that overflow or blow up the root search
    ("drill_sim", ["simulate", "--dt", "1e-320"], ["--dt 1e-320", "expected a time step"]),
    ("drill_sim", ["stability", "--re-min", "-1000"], ["--re-min -1000", "expected", "-100"]),
    ("drill_sim", ["stability", "--re-min=-1e308"], ["--re-min -1e308", "expected"]),
    ("drill_sim", ["stability", "--rpm", "0.001"], ["--rpm 0.001", "roots", "raise --rpm"]),
    ("drill_sim", ["stability", "--rpm=1e-320"], ["--rpm 1e-320", "expected"]),
    ("drill_sim", ["stability", "--groups", GROUPS, "--w0", "9.6", "--omega0=1e-320"],
     ["--omega0 1e-320", "expected"]),
    ("drill_sim", ["stability", "--groups", GROUPS, "--w0=1e308", "--omega0", "1.32"],
     ["--w0 1e308", "expected"]),
    ("drill_sim", ["stability", "--re-min", "-50"], ["--re-min -50", "roots", "expected"]),
    ("drill_sim", ["stability", "--rpm", "0"], ["--rpm 0", "expected"]),
    # parameters given outside --ros-args, which ROS would ignore
    ("drill_sim_node", ["-p", "rate_hz:=100"], ["outside --ros-args are not read: -p rate_hz:=100",
                                                "expected them after --ros-args"]),
    ("drill_sim_controller", ["enabled", "--ros-args", "-p", "law:=z_torque"],
     ["not read: enabled"]),
    # recorder and player options
    ("drill_sim_replay", ["{bag}", "--rate", "1e-300", "--wait-for", "0"],
     ["--rate 1e-300", "expected a playback speed"]),
    ("drill_sim_replay", ["{bag}", "--queue-depth", "99999999999", "--wait-for", "0"],
     ["--queue-depth 99999999999", "expected"]),
    ("drill_sim_replay", ["{bag}", "--rate", "-1e3"], ["--rate -1e3", "expected"]),
    ("drill_sim_record", ["-a", "-d", "inf", "-o", "{root}/rec_inf", "--duration", "1"],
     ["--max-bag-duration inf", "expected"]),
    ("drill_sim_record", ["-a", "--queue-depth", "99999999999", "-o", "{root}/rec_q",
                          "--duration", "1"], ["--queue-depth 99999999999", "expected"]),
    # runs too long or too big to hold
    ("drill_sim", ["simulate", "--duration", "1e9"], ["--duration 1e9", "steps", "expected"]),
    ("drill_sim", ["simulate", "--duration", "3e6"], ["--duration 3e6", "steps", "expected"]),
    ("drill_sim", ["simulate", "--duration", "1e6", "--dt", "1e-6"],
     ["--duration 1e6", "--dt 1e-6", "hours", "expected at most"]),
    ("drill_sim", ["simulate", "--duration", "2e4", "--out", "{root}/big.csv"],
     ["--duration 2e4", "samples", "GB", "expected at most"]),
    # physical inputs out of range, named as typed
    ("drill_sim", ["simulate", "--rpm", "1e308"], ["--rpm 1e308", "expected", "rpm"]),
    ("drill_sim", ["simulate", "--duration", "1e308"], ["--duration 1e308", "expected"]),
    ("drill_sim", ["simulate", "--hook-load-kn", "1e308"], ["--hook-load-kn 1e308", "kN"]),
    ("drill_sim", ["simulate", "--wob-kn", "-1e6"], ["--wob-kn -1e6", "expected", "kN"]),
    ("drill_sim", ["simulate", "--start", "rest", "--gap", "-1e-3"], ["--gap -1e-3", "m"]),
    ("drill_sim", ["simulate", "--gap", "1e300", "--start", "rest"], ["--gap 1e300"]),
    ("drill_sim", ["simulate", "--gap", "0.05"], ["--gap 0.05", "does nothing with the default",
                                                  "expected it with --start rest"]),
    ("drill_sim", ["simulate", "--gap", "0.05", "--start", "steady"],
     ["--gap 0.05 does nothing with --start steady"]),
    ("drill_sim", ["simulate", "--perturbation", "5"], ["--perturbation 5", "expected"]),
    ("drill_sim", ["simulate", "--groups", GROUPS, "--w0", "-1e4", "--omega0", "1"],
     ["--w0 -1e4", "expected"]),
    ("drill_sim", ["simulate", "--groups", GROUPS, "--w0", "9.6", "--omega0", "1e3"],
     ["--omega0 1e3", "expected"]),
    ("drill_sim", ["simulate", "--groups", "n=4,psi=1e300,lambda=6.84,beta=0.36", "--w0",
                   "9.6", "--omega0", "1"], ["psi = 1e300", "expected"]),
    ("drill_sim", ["simulate", "--metrics-window", "-inf"], ["--metrics-window -inf"]),
    ("drill_sim", ["simulate", "--output-interval", "-1e-3"], ["--output-interval -1e-3"]),
    # one rule for a bag's folder, and no contradiction
    ("drill_sim", ["run", "--no-record", "--record", "{root}/both", "--duration", "1"],
     ["--no-record", "--record {root}/both", "expected"]),
    ("drill_sim", ["run", "--record", "{root}/no/such/bag", "--duration", "1"],
     ["--record {root}/no/such/bag", "folder {root}/no/such does not exist",
      "expected a new name in an existing folder"]),
    ("drill_sim_record", ["-a", "-o", "{root}/no/such/bag", "--duration", "1"],
     ["-o/--output {root}/no/such/bag", "folder {root}/no/such does not exist",
      "expected a new name in an existing folder"]),
]


def _case(program: str, args: list[str], fragments: list[str]):
    """A case as a parameter: named by its command line; marked offline where it starts no
    node (the command line's simulate and stability), else untimed (its node is refused)."""
    offline = program == "drill_sim" and args[0] in ("simulate", "stability")
    return pytest.param(program, args, fragments, id=f"{program} {' '.join(args)}",
                        marks=[pytest.mark.offline if offline else UNTIMED])


@pytest.mark.parametrize("program, args, fragments", [_case(*case) for case in CASES])
def test_bad_input_ends_in_one_clear_line(files, program, args, fragments):
    from rosutil import isolate
    isolate()
    fill = {k: str(v) for k, v in files.items()}
    proc = run(program, *(a.format(**fill) for a in args), cwd=files["root"])
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr and proc.stdout == ""
    for fragment in fragments:
        assert fragment.format(**fill) in lines[0], lines[0]
    assert not (files["root"] / "no").exists()          # no folder made on the way


@pytest.mark.offline
def test_negative_numbers_in_any_notation_are_values():
    for args in (["--wob-kn", "-1e1"], ["--wob-kn", "-10"], ["--wob-kn=-1e1"]):
        proc = run("drill_sim", "simulate", *args, "--duration", "1", "--json")
        assert proc.returncode == 0, proc.stderr
        assert _strict(proc.stdout)["available_weight"] == pytest.approx(-10e3)
    proc = run("drill_sim", "stability", "--re-min", "-2e-1", "--json")
    assert proc.returncode == 0, proc.stderr
    assert _strict(proc.stdout)["re_min"] == pytest.approx(-0.2)


def test_join_negative_values():
    assert join_negative_values(["simulate", "--wob-kn", "-1e1", "--gap", "-inf", "-r", "-2",
                                 "--json", "x", "--", "--a", "-1e3"]) == [
        "simulate", "--wob-kn=-1e1", "--gap=-inf", "-r-2", "--json", "x", "--", "--a", "-1e3"]
    assert join_negative_values(["run", "--ros-args", "-p", "-1e3"]) == [
        "run", "--ros-args", "-p", "-1e3"]
    assert join_negative_values(["--topics", "-x"]) == ["--topics", "-x"]


@pytest.mark.offline
def test_json_is_strict_where_a_quantity_is_undefined():
    # the bit never turns: the SSI (spread over mean speed) is undefined, printed as null
    proc = run("drill_sim", "simulate", "--groups", "n=1,psi=0.01,lambda=1000,beta=10", "--w0",
               "1000", "--omega0", "0.001", "--duration", "20", "--json")
    assert proc.returncode == 0, proc.stderr
    summary = _strict(proc.stdout)
    assert summary["ssi"] is None and summary["mean_bit_speed"] == 0.0
    assert json_line({"a": float("nan"), "b": [float("inf"), 1.5]}) \
        == '{"a": null, "b": [null, 1.5]}'
    assert finite_or_none((1, -float("inf"))) == [1, None]


@pytest.mark.offline
def test_metrics_window_may_be_the_whole_run():
    proc = run("drill_sim", "simulate", "--duration", "2", "--metrics-window", "2", "--json")
    assert proc.returncode == 0, proc.stderr
    assert _strict(proc.stdout)["metrics_window"] == [0.0, 2.0]


@pytest.mark.offline
def test_stability_refusal_names_a_speed_that_works():
    proc = run("drill_sim", "stability", "--rpm", "9")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    least = re.search(r"raise --rpm to ([0-9.]+) or more", proc.stderr)
    assert least, proc.stderr
    ok = run("drill_sim", "stability", "--rpm", least.group(1), "--json")
    assert ok.returncode == 0, ok.stderr
    assert _strict(ok.stdout)["complete"]


@pytest.mark.offline
def test_limits_themselves_are_accepted(tmp_path):
    for args in (["--rpm", "400", "--duration", "1"], ["--rpm", "0", "--duration", "1"],
                 ["--wob-kn", "-338", "--duration", "1"],
                 ["--groups", GROUPS, "--w0", "1000", "--omega0", "50", "--duration", "5"],
                 ["--start", "rest", "--gap", "10", "--duration", "1"]):
        proc = run("drill_sim", "simulate", *args, "--json")
        assert proc.returncode == 0, (args, proc.stderr)
        _strict(proc.stdout)
    proc = run("drill_sim", "simulate", "--duration", "2", "--plot", str(tmp_path / "f.svg"))
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "f.svg").read_text().lstrip().startswith("<?xml")


def test_binary_preset_or_scenario_is_a_parameter_error(tmp_path):
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"\x00\xff\xfe")
    with pytest.raises(ParameterError, match=r"binary\.yaml.* is not a text file"):
        load_preset(binary)
    with pytest.raises(ParameterError, match=r"binary\.yaml.* is not a text file"):
        load_scenario(binary)
