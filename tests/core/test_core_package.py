"""The core's names load on first use: each is what its module defines, never a module."""

import importlib
import pkgutil
import subprocess
import sys
import types

import drill_sim.core as core


def test_every_name_is_its_modules_definition_even_after_every_module_is_imported():
    for info in pkgutil.iter_modules(core.__path__):
        importlib.import_module(f"drill_sim.core.{info.name}")
    for name in core.__all__:
        value = getattr(core, name)
        assert not isinstance(value, types.ModuleType), name


def test_the_bag_tools_read_the_stick_slip_definition_without_the_kernels():
    code = ("import sys, drill_sim.bag.series, drill_sim.bag.rig_stats; "
            "print('numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
