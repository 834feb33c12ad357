"""A kernel's numba cache follows the files it inlines (``core.numba_cache``): an edit of the
shared bit-rock laws must not leave a kernel running the cached code of the old ones."""

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


def test_the_kernels_follow_the_shared_laws():
    for module in ("kernel", "distributed_kernel", "sensors"):     # each registers itself
        importlib.import_module(f"drill_sim.core.{module}")
    follows = {os.path.basename(k): sorted(os.path.basename(f) for f in v)
               for k, v in numba_cache._FOLLOWS.items()}
    assert follows["kernel.py"] == ["bit_rock.py"]
    assert follows["distributed_kernel.py"] == ["bit_rock.py", "kernel.py"]
    assert follows["sensors.py"] == ["stick_slip.py"]
    assert numba_cache.FollowingLocator in numba_cache._IMPL._locator_classes
