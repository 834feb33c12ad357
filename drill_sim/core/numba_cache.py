"""numba caches a kernel's machine code under a hash of its own file alone, not of the files of
the functions it inlines: after an edit of ``bit_rock.py`` the lumped and distributed kernels
would go on running the cached code of the old laws. ``follow`` makes a kernel file's cache
stamp cover those files too (a locator for the kernels' files, tried before numba's own)."""

from __future__ import annotations

import functools
import hashlib
import os

from numba.core import caching

_FOLLOWS: dict[str, tuple[str, ...]] = {}      # a kernel file -> the files it inlines


def follow(kernel_file: str, *inlined_files: str) -> None:
    """Tie the numba cache of the functions defined in ``kernel_file`` (from here on) to the
    contents of ``inlined_files`` as well as its own. Call it before they are defined."""
    _FOLLOWS[os.path.realpath(kernel_file)] = tuple(os.path.realpath(f) for f in inlined_files)


@functools.cache
def _content(path: str, mtime_ns: int, size: int) -> bytes:
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).digest()


def _stamp(path: str) -> bytes:
    st = os.stat(path)
    return _content(path, st.st_mtime_ns, st.st_size)


# numba's in-tree locator (its name has changed between releases); without it, numba's own
_IN_TREE = getattr(caching, "InTreeCacheLocator", None) or getattr(
    caching, "_InTreeCacheLocator", None)
_IMPL = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)

if _IN_TREE is not None and _IMPL is not None:
    class FollowingLocator(_IN_TREE):                   # type: ignore[misc, valid-type]
        """The in-tree locator for a kernel file that ``follow`` named: its stamp is the
        hashes of the file and of every file it inlines."""

        @classmethod
        def from_function(cls, py_func, py_file):
            if os.path.realpath(py_file) not in _FOLLOWS:
                return None
            return super().from_function(py_func, py_file)

        def get_source_stamp(self):
            own = super().get_source_stamp()
            return own, tuple(_stamp(f) for f in _FOLLOWS[os.path.realpath(self._py_file)])

    _classes = _IMPL._locator_classes
    if not any(c.__name__ == "FollowingLocator" for c in _classes):
        _classes.insert(_classes.index(_IN_TREE), FollowingLocator)
