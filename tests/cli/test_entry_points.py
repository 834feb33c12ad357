"""Every installed program stops quietly on a Ctrl-C that comes while it is still importing
(a session stopped right after it started its clients printed their tracebacks)."""

from __future__ import annotations

import re
import signal
import subprocess
import time
from pathlib import Path

import pytest
from conftest import installed

PROGRAMS = re.findall(r'"(drill_sim\w*) = drill_sim\.entry_points:\w+"',
                      (Path(__file__).resolve().parents[2] / "setup.py").read_text())


def test_every_program_starts_through_the_entry_points():
    assert sorted(PROGRAMS) == ["drill_sim", "drill_sim_controller", "drill_sim_drive",
                                "drill_sim_node", "drill_sim_record", "drill_sim_replay"]


@pytest.mark.parametrize("program", ["drill_sim_drive", "drill_sim_controller",
                                     "drill_sim_node"])
def test_a_ctrl_c_while_importing_stops_quietly(program):
    proc = subprocess.Popen([installed(program)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    # past the interpreter's own start (which no program can guard) and into the program's
    # imports: numpy and numba loaded make it over 40 MB (the bare interpreter ~15 MB)
    status = Path(f"/proc/{proc.pid}/status")
    end = time.monotonic() + 60.0
    while time.monotonic() < end and proc.poll() is None:
        rss = [int(line.split()[1]) for line in status.read_text().splitlines()
               if line.startswith("VmRSS:")]
        if rss and rss[0] > 40_000:
            break
        time.sleep(0.005)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert "Traceback" not in err, err
    assert proc.returncode in (0, 130), (proc.returncode, err)
