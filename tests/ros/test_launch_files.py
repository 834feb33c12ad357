"""The shipped launch files (``launch/*.launch.xml``) name only what exists: every executable
is an installed entry point, every parameter is in that node's parameter table (or the
controller's), every params file is shipped, every ``$(var ...)`` is declared, and the
recorder's arguments parse. ``ros2 launch`` itself is not installable here, so the files are
checked against the package, not run."""

from __future__ import annotations

import argparse
import re
import xml.etree.ElementTree as ET
from importlib.metadata import entry_points
from pathlib import Path

import pytest
import yaml

from drill_sim.cli import record
from drill_sim.control.supervisor import law_gain_defaults
from drill_sim.core import load_preset
from drill_sim.ros.controller import CONTROL_LAWS, PARAMETERS
from drill_sim.session.parameter_table import specs

ROOT = Path(__file__).resolve().parents[2]
LAUNCH = sorted((ROOT / "launch").glob("*.launch.xml"))
PROGRAMS = {e.name for e in entry_points(group="console_scripts") if e.value.startswith(
    "drill_sim.")}
NODE_PARAMETERS = {s.name for s in specs(load_preset("base"))} | {"preset", "use_sim_time"}
CONTROLLER_PARAMETERS = {name for name, _, _ in PARAMETERS} | {"use_sim_time"} | {
    f"{law}.{gain}" for law in CONTROL_LAWS for gain in law_gain_defaults(law, 300.0, 2900.0)}
KNOWN = {"drill_sim_node": NODE_PARAMETERS, "drill_sim_controller": CONTROLLER_PARAMETERS}
SHARE = "$(find-pkg-share drill_sim)/"


def _substituted(text: str, args: dict[str, str], where: str) -> str:
    for name in re.findall(r"\$\(var ([^)]+)\)", text):
        assert name in args, f"{where}: $(var {name}) is not declared"
        text = text.replace(f"$(var {name})", args[name])
    if SHARE in text:                     # installed from the package's folders (setup.py)
        text = str(ROOT / "drill_sim" / text.split(SHARE, 1)[1])
    assert "$(" not in text, f"{where}: {text}"
    return text


def test_the_four_launch_files_are_shipped_and_installed():
    assert {p.name for p in LAUNCH} == {
        "rig.launch.xml", "rig_controller.launch.xml", "rig_record.launch.xml",
        "lockstep_controller.launch.xml"}
    assert '("share/" + package_name + "/launch", glob("launch/*.launch.xml"))' in \
        (ROOT / "setup.py").read_text()


@pytest.mark.parametrize("path", LAUNCH, ids=lambda p: p.name)
def test_every_executable_and_parameter_exists(path):
    root = ET.parse(path).getroot()
    assert root.tag == "launch"
    args = {a.get("name"): a.get("default", "") for a in root.iter("arg")}
    nodes = list(root.iter("node"))
    assert nodes, f"{path.name}: no node"
    for node in nodes:
        where = f"{path.name}: {node.get('exec')}"
        assert node.get("pkg") == "drill_sim", where
        assert node.get("exec") in PROGRAMS, f"{where}: not an installed program"
        known = KNOWN.get(node.get("exec"))
        for param in node.iter("param"):
            if param.get("from") is not None:
                file = Path(_substituted(param.get("from"), args, where))
                assert file.is_file(), f"{where}: {file} is not shipped"
                given = yaml.safe_load(file.read_text())["/**"]["ros__parameters"]
                assert set(given) <= known, f"{where}: {set(given) - known}"
                continue
            assert param.get("name") in known, f"{where}: no parameter {param.get('name')}"
            _substituted(param.get("value", ""), args, where)
        if node.get("exec") == "drill_sim_record":
            parser = argparse.ArgumentParser()
            record.add_arguments(parser)
            parsed = parser.parse_args(_substituted(node.get("args", ""), args, where).split())
            assert parsed.regex, where
        else:
            assert node.get("args") is None, where


def test_a_misspelt_parameter_would_be_caught(tmp_path):
    """The check itself: a launch file with a parameter the rig does not have fails it."""
    bad = tmp_path / "bad.launch.xml"
    bad.write_text('<launch><node pkg="drill_sim" exec="drill_sim_node">'
                   '<param name="rate_hz_typo" value="1.0"/></node></launch>')
    with pytest.raises(AssertionError, match="rate_hz_typo"):
        test_every_executable_and_parameter_exists(bad)
