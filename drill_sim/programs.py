"""Where the package's installed programs are: beside the running interpreter (a virtual
environment's ``bin/``), else on ``PATH``. Every program that starts another (``drill_sim run``,
``drill_sim control --ros``) and the tests find them here."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path


def program(name: str) -> str:
    """The path of the installed program ``name``; OSError naming it if it is not installed."""
    beside = Path(sys.executable).parent / name
    found = str(beside) if beside.exists() else shutil.which(name)
    if found is None:
        raise OSError(f"{name} is not installed beside {sys.executable} nor on PATH "
                      "(pip install the package first)")
    return found
