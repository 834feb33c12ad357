"""A kernel's numba cache follows the files it inlines (``core.numba_cache``): an edit of the
shared bit-rock laws or of the state's layout must not leave a kernel running the cached code
of the old ones."""

import importlib
import os

from drill_sim.core import numba_cache


def test_a_kernels_stamp_changes_with_a_file_it_inlines(tmp_path):
    kernel, laws = tmp_path / "kernel_x.py", tmp_path / "laws_x.py"
    kernel.write_text("def f():\n    return 1\n")
    laws.write_text("A = 1\n")
    numba_cache.follow(str(kernel), str(laws))

    def stamp():
        locator = numba_cache.FollowingLocator.from_function(lambda: None, str(kernel))
        return locator.get_source_stamp()

    before = stamp()
    laws.write_text("A = 2\n")
    os.utime(laws, ns=(1, 1))                  # a content change, whatever the clock says
    assert stamp() != before
    laws.write_text("A = 1\n")
    os.utime(laws, ns=(2, 2))
    assert stamp() == before                   # the stamp is the contents'


def test_the_kernels_follow_the_shared_laws_and_the_state_layout():
    """Each compiled module follows what it compiles in: the laws, the state's layout (its
    indices are constants in the machine code: a slot added must not leave a kernel indexing
    by the old layout), and for the vector step every kernel and helper it calls."""
    for module in ("core.kernel", "core.distributed_kernel", "core.sensors", "core.rig_step",
                   "gym.vector_step"):     # each registers itself
        importlib.import_module(f"drill_sim.{module}")
    follows = {os.path.basename(k): sorted(os.path.basename(f) for f in v)
               for k, v in numba_cache._FOLLOWS.items()}
    assert follows["kernel.py"] == ["bit_rock.py", "state_layout.py"]
    assert follows["distributed_kernel.py"] == ["bit_rock.py", "kernel.py", "state_layout.py"]
    assert follows["sensors.py"] == ["stick_slip.py"]
    assert follows["rig_step.py"] == ["state_layout.py"]
    assert follows["vector_step.py"] == sorted(
        ["kernel.py", "distributed_kernel.py", "bit_rock.py", "state_layout.py", "rig_step.py",
         "sensors.py", "stick_slip.py", "payoff.py"])
    assert numba_cache.FollowingLocator in numba_cache._IMPL._locator_classes
