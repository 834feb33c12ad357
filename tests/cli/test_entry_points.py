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


@pytest.mark.parametrize("program, sig, inherited", [
    ("drill_sim_drive", signal.SIGINT, signal.SIG_DFL),
    ("drill_sim_controller", signal.SIGINT, signal.SIG_DFL),
    ("drill_sim_node", signal.SIGINT, signal.SIG_DFL),
    ("drill_sim_node", signal.SIGINT, signal.SIG_IGN),     # started in the background by a shell
    ("drill_sim_node", signal.SIGTERM, signal.SIG_DFL),
])
def test_a_ctrl_c_while_importing_stops_quietly(program, sig, inherited):
    """A SIGINT or SIGTERM while the program imports stops it quietly (status 128 + signal,
    or 0 if it was already past its imports), also when SIGINT was inherited as ignored (a
    program started with '&' by a script: the signal was lost and the node ran on)."""
    proc = subprocess.Popen([installed(program)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, inherited))
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
    proc.send_signal(sig)
    try:
        # generous: a first start on a loaded machine compiles its kernels before it checks
        _, err = proc.communicate(timeout=180)
    finally:
        if proc.poll() is None:                  # it ran on: the signal was lost
            proc.kill()
            proc.communicate()
    assert "Traceback" not in err, err
    assert proc.returncode in (0, 128 + sig), (proc.returncode, err)


def test_a_node_started_with_sigint_ignored_still_stops_on_it():
    """Up and running after SIGINT was inherited as ignored: a SIGINT stops the node cleanly."""
    import os
    env = dict(os.environ, ROS_DOMAIN_ID=str(150 + os.getpid() % 50),
               ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    proc = subprocess.Popen([installed("drill_sim_node")], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, env=env,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN))
    lines = []
    for line in proc.stdout:                     # wait for the event, not a fixed time
        lines.append(line)
        if "ready" in line:
            break
    proc.send_signal(signal.SIGINT)
    try:
        rest, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, "".join(lines) + rest
    assert "Traceback" not in rest


def test_a_signal_whose_exit_an_import_swallowed_still_stops_the_program(tmp_path, monkeypatch):
    """A library that catches BaseException around its own imports eats the SystemExit that
    the signal raised; the program must stop all the same (status 128 + signal) instead of
    running on, once the import is done."""
    import sys

    from drill_sim import entry_points
    (tmp_path / "swallowing.py").write_text(
        "import os, signal\n"
        "try:\n"
        "    os.kill(os.getpid(), signal.SIGINT)\n"
        "    sum(range(10_000))           # the handler runs here, between two bytecodes\n"
        "except BaseException:\n"
        "    pass\n"
        "def main():\n"
        "    raise AssertionError('ran on after the signal')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(entry_points, "_SIGNALLED", [])
    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        assert entry_points._main("swallowing") == 128 + signal.SIGINT
    finally:
        for s, handler in saved.items():
            signal.signal(s, handler)
        sys.modules.pop("swallowing", None)
