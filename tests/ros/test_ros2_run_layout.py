"""The package builds with colcon and its executables are where ``ros2 run`` looks for them."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import installed
from rosutil import isolate

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.untimed("a build and a lookup: the node need only say it is ready, within 60 s")
def test_colcon_build_and_ros2_run_lookup(tmp_path):
    src = tmp_path / "src" / "drill_sim"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
        ".venv", ".git", "build", "install", "log", "__pycache__", "*.egg-info", ".*cache"))
    build = subprocess.run([installed("colcon"), "build", "--base-paths", "src"], cwd=tmp_path,
                           capture_output=True, text=True, timeout=600)
    assert build.returncode == 0, build.stdout + build.stderr
    prefix = tmp_path / "install" / "drill_sim"
    env = dict(os.environ, AMENT_PREFIX_PATH=str(prefix))
    # ros2 run: get_package_prefix(pkg) + lib/<pkg>/ + an executable file
    probe = ("from ament_index_python.packages import get_package_prefix as g;"
             "print(g('drill_sim'))")
    found = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True,
                           text=True, check=True).stdout.strip()
    assert Path(found) == prefix
    exe = Path(found) / "lib" / "drill_sim" / "drill_sim_node"
    assert exe.is_file() and os.access(exe, os.X_OK)
    for name in ("drill_sim_drive", "drill_sim_record", "drill_sim_replay"):
        assert (Path(found) / "lib" / "drill_sim" / name).is_file(), name
    assert (prefix / "share" / "drill_sim" / "package.xml").is_file()
    launch = {p.name for p in (prefix / "share" / "drill_sim" / "launch").glob("*.launch.xml")}
    assert launch == {p.name for p in (ROOT / "launch").glob("*.launch.xml")} and launch
    for config in ("drill_sim.yaml", "foxglove_layout.json", "plotjuggler_layout.xml"):
        assert (prefix / "share" / "drill_sim" / "config" / config).is_file(), config
    # run it the way ros2 run would, from the install space
    isolate()
    site = next((prefix / "lib").glob("python3*/site-packages"))
    env["PYTHONPATH"] = os.pathsep.join([str(site), env.get("PYTHONPATH", "")])
    proc = subprocess.Popen([str(exe), "--ros-args", "--params-file",
                             str(prefix / "share" / "drill_sim" / "config" / "drill_sim.yaml")],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            cwd=tmp_path)
    lines = []
    end = time.monotonic() + 60
    while time.monotonic() < end:
        line = proc.stdout.readline()
        lines.append(line)
        if "ready" in line or not line:
            break
    proc.send_signal(2)
    rest, _ = proc.communicate(timeout=120)   # a fresh install may still be compiling kernels
    assert any("rig 'base' ready" in line for line in lines), "".join(lines) + rest
    assert proc.returncode == 0, "".join(lines) + rest
