"""Shared fixtures: the literature parameter set and a few regimes of it."""

from __future__ import annotations

import os

os.environ.setdefault("NUMBA_NRT_STATS", "1")   # lets tests count the kernel's heap allocations

import shutil
import sys
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
    beside = Path(sys.executable).parent / name
    found = str(beside) if beside.exists() else shutil.which(name)
    if found is None:
        pytest.fail(f"{name} is not installed: run the README's test command")
    return found


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
