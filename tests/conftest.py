"""Shared fixtures (the literature parameter set and a few regimes of it), and the suite's
markers, applied here automatically:

- ``process``: the test starts a program (an installed entry point, in a subprocess). Found
  from the code: the test, the fixtures it asks for and the module's helpers they call name
  ``subprocess``, ``NodeProcess`` or ``installed``; a test not so marked that starts one all
  the same fails, naming the rule (so the inner loop below never starts a program).
- ``ros``: the test needs rclpy (its module imports it, or it asks for the ``ros`` fixture).
- ``slow``: a long validation run, marked by hand with the reason it must be long
  (``@pytest.mark.slow("why")``).
- ``offline``, by hand: the programs the test starts run offline (no node, no ROS: the
  command line's simulate, stability, map, bag): unlike the other process tests, which one
  worker runs one at a time, these may run in the other worker beside them.
- ``untimed``, by hand with the reason: the test's node exits at once or its test asserts
  nothing that a busy machine could delay past a limit (a refusal, a build, a lookup); it
  runs in the other worker as the offline ones do.

The inner loop is ``pytest -m "not process and not slow"``."""

from __future__ import annotations

import os

os.environ.setdefault("NUMBA_NRT_STATS", "1")   # lets tests count the kernel's heap allocations

import ast
import subprocess
import sys
from functools import cache
from pathlib import Path

import pytest

from drill_sim.core import Groups, load_preset


@pytest.fixture(scope="session")
def base():
    return load_preset("base")


@pytest.fixture(scope="session")
def base_groups(base) -> Groups:
    return base.rig.groups


@pytest.fixture(scope="session")
def base_commands(base) -> tuple[float, float]:
    """(w0, omega0) of the base preset's 100 kN and 60 rpm: a stick-slip regime."""
    sc = base.rig.scales
    return 1e3 * base.weight_on_bit_kn / sc.force_n, base.top_drive_speed_rad_s * sc.time_s


def installed(name: str) -> str:
    """Path of a console script installed beside this interpreter (or on PATH); fail if absent."""
    from drill_sim.programs import program
    try:
        return program(name)
    except OSError as exc:
        pytest.fail(f"{exc}: run the README's test command")


@pytest.fixture(scope="module")
def ros(request):
    """A ROS test client node on this run's own domain; rclpy is imported only by ROS tests."""
    import rclpy
    from rosutil import isolate

    isolate()
    rclpy.init()
    node = rclpy.create_node("test_client_" + request.module.__name__.replace(".", "_"))
    yield node
    node.destroy_node()
    rclpy.shutdown()


# ---- markers ------------------------------------------------------------------------------
# names that start a program: the standard ones, the test helpers', and the package's own
# functions that start its programs (``drill_sim control --ros``'s scoring run)
STARTS_A_PROGRAM = {"subprocess", "NodeProcess", "installed", "Popen", "run_ros"}
TESTS = Path(__file__).resolve().parent
# the programs the guard below watches for: the package's entry points and Python itself
OURS = {"drill_sim", "drill_sim_node", "drill_sim_drive", "drill_sim_controller",
        "drill_sim_record", "drill_sim_replay", "ruff", "colcon", Path(sys.executable).name,
        "python", "python3"}


def pytest_configure(config) -> None:
    config.addinivalue_line("markers", "process: starts a program (an installed entry point)")
    config.addinivalue_line("markers", "ros: needs rclpy")
    config.addinivalue_line("markers", "slow(reason): a long validation run, and why it is long")
    config.addinivalue_line("markers", "offline: the programs the test starts start no node")
    config.addinivalue_line("markers", "untimed(reason): its node programs assert nothing a "
                            "busy machine could delay, and why")
    _programs_can_be_grouped(config)


def _programs_can_be_grouped(config) -> None:
    """Refuse ``--dist loadgroup`` where the ``programs`` group would be silently ignored:
    pytest 9.2 keeps node ids where pytest-xdist 3.8 writes a test's group, so the programs
    ran on both workers at once, sharing the cores they are timed on."""
    from importlib.metadata import version
    if config.getoption("dist", "no") != "loadgroup":
        return
    xdist = tuple(int(x) for x in version("pytest-xdist").split(".")[:3] if x.isdigit())
    if pytest.version_tuple[:2] >= (9, 2) and xdist <= (3, 8, 0):
        raise pytest.UsageError(
            f"pytest {pytest.__version__} with pytest-xdist {version('pytest-xdist')} ignores "
            "xdist groups, and the tests that start programs must run one at a time: install "
            "the 'test' extra's versions (pip install -e '.[test]')")


_READING: set[str] = set()      # modules being read (test modules may import each other)


@cache
def _module_facts(path: str) -> tuple[frozenset[str], bool]:
    """(the module's functions that start a program, directly or through the module's other
    functions; whether the module imports ROS)."""
    tree = ast.parse(Path(path).read_text())
    functions = {n.name: n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)}
    names = {name: {x.id for x in ast.walk(f) if isinstance(x, ast.Name)}
             | {x.attr for x in ast.walk(f) if isinstance(x, ast.Attribute)}
             for name, f in functions.items()}
    # helpers imported from another test module that start a program
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and not node.level:
            found = list(TESTS.rglob(node.module.replace(".", "/") + ".py"))
            if found and str(found[0]) not in _READING:
                _READING.add(path)
                try:
                    theirs = _module_facts(str(found[0]))[0]
                finally:
                    _READING.discard(path)
                imported |= {a.asname or a.name for a in node.names if a.name in theirs}
    programs = STARTS_A_PROGRAM | imported
    starting = {n for n, used in names.items() if used & programs}
    grown = True
    while grown:
        more = {n for n, used in names.items() if n not in starting and used & starting}
        starting |= more
        grown = bool(more)
    text = Path(path).read_text()
    uses_ros = "import rclpy" in text or "from rclpy" in text or "rosutil" in text
    return frozenset(starting), uses_ros


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items) -> None:
    conftest_starting = _module_facts(__file__)[0] - {"_programs_only_where_marked"}
    for item in items:
        path = str(item.path)
        starting, uses_ros = _module_facts(path)
        function = getattr(item, "function", None)
        name = getattr(function, "__name__", "")
        fixtures = set(getattr(item, "fixturenames", ()))
        if name in starting or fixtures & (starting | conftest_starting):
            item.add_marker(pytest.mark.process)
            # one worker runs the programs, one at a time (they need the machine's cores and
            # their own ROS domain, as in a serial run); the other worker runs the rest, and
            # the offline programs (no node: nothing of theirs runs in real time)
            if (item.get_closest_marker("offline") is None
                    and item.get_closest_marker("untimed") is None):
                item.add_marker(pytest.mark.xdist_group("programs"))
        if uses_ros or "ros" in fixtures:
            item.add_marker(pytest.mark.ros)
        for kind, why in (("slow", "the run must be long"),
                          ("untimed", "nothing of it waits on the machine's speed")):
            for mark in item.iter_markers(kind):
                if not (mark.args or mark.kwargs.get("reason")):
                    raise pytest.UsageError(f"{item.nodeid}: @pytest.mark.{kind} needs the "
                                            f"reason {why}")


@pytest.fixture(autouse=True)
def _programs_only_where_marked(request, monkeypatch):
    """A test not marked ``process`` that starts a program fails, naming the rule."""
    if request.node.get_closest_marker("process") is not None:
        yield
        return
    real = subprocess.Popen.__init__

    def refuse(self, args, *rest, **kwargs):
        program = Path(str(args[0] if isinstance(args, (list, tuple)) else args).split()[0])
        if program.name not in OURS:               # a library's own helper (fc-list...)
            return real(self, args, *rest, **kwargs)
        raise AssertionError(f"{request.node.nodeid} starts a program ({args!r}) but is not "
                             "marked 'process': name subprocess, NodeProcess or installed in "
                             "the test or a fixture or helper of its module")

    monkeypatch.setattr(subprocess.Popen, "__init__", refuse)
    yield
    monkeypatch.setattr(subprocess.Popen, "__init__", real)
