"""Checks of command-line values shared by every program: numbers within documented ranges,
output files and plot formats, new bag directories, strict JSON, and negative numbers as
option values. Every refusal is a ``UsageError`` whose one line names what the user typed,
what is wrong with it and what was expected.
"""

from __future__ import annotations

import argparse
import json
import math
import os
from collections.abc import Sequence
from pathlib import Path

from .errors import UsageError


class Number(float):
    """A float read from the command line that remembers how the user wrote it."""

    typed: str

    def __new__(cls, text: str) -> Number:
        value = super().__new__(cls, text)
        value.typed = text
        return value


def number(text: str) -> float:
    """argparse ``type`` for real numbers: a ``Number``, or a message naming the text."""
    try:
        return Number(text.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number; expected a decimal number "
                                         "such as 60, -0.5 or 1e-3") from None


def integer(text: str) -> int:
    """argparse ``type`` for counts: an int, or a message naming the text."""
    try:
        return int(text.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number; expected digits "
                                         "such as 1000") from None


def typed(value: float) -> str:
    """``value`` as the user typed it (or as Python prints it, for defaults and results)."""
    return getattr(value, "typed", repr(value))


def in_range(name: str, value: float, low: float, high: float, *, unit: str = "",
             what: str = "", note: str = "", low_open: bool = False) -> float:
    """``value`` if finite and within ``low``..``high`` (``low`` excluded if ``low_open``),
    else UsageError (``what`` the value is; ``note`` follows the range), such as
    "--rpm 1e308: out of range; expected a top-drive speed 0 to 400 rpm"."""
    ok = math.isfinite(value) and (value > low if low_open else value >= low) and value <= high
    if not ok:
        span = (f"greater than {_fmt(low)} and up to {_fmt(high)}" if low_open
                else f"{_fmt(low)} to {_fmt(high)}")
        problem = "out of range" if math.isfinite(value) else "not a finite number"
        raise UsageError(f"{name} {typed(value)}: {problem}; expected "
                         f"{what + ' ' if what else ''}{span}{' ' + unit if unit else ''}"
                         f"{' ' + note if note else ''}")
    return float(value)


def _fmt(x: float) -> str:
    """A range limit: whole numbers in full (10,000), others to four digits."""
    return f"{int(x):,}" if x == int(x) and abs(x) < 1e15 else f"{x:.4g}"


def whole(name: str, value: int, low: int, high: int, *, unit: str = "", what: str = "") -> int:
    """``value`` if within ``low``..``high``, else UsageError naming the range."""
    if not low <= value <= high:
        u = f" {unit}" if unit else ""
        raise UsageError(f"{name} {value}: out of range; expected {what + ' ' if what else ''}"
                         f"a whole number {low:,} to {high:,}{u}")
    return value


def sensor_seed(value: int, name: str = "--sensor-seed") -> int:
    """A sensor-noise seed, in the one range every tool and the node take."""
    from ..core.sensors import MAX_SENSOR_SEED
    return whole(name, value, 0, MAX_SENSOR_SEED, what="a sensor seed:")


# ---- output files ------------------------------------------------------------------------------
def output_file(name: str, path: Path) -> Path:
    """A file the program will write at the end: its folder must exist and be writable, and it
    must not be a folder itself, so that a long run is not lost at the last step."""
    folder = path.parent
    if path.is_dir():
        raise UsageError(f"{name} {path}: is a folder; expected a file name")
    if not folder.is_dir():
        raise UsageError(f"{name} {path}: folder {folder} does not exist; expected a file in an "
                         "existing folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise UsageError(f"{name} {path}: folder {folder} is not writable; expected a file in a "
                         "folder you can write to")
    return path


def plot_formats() -> list[str]:
    """The file extensions matplotlib can write, without the dot."""
    from matplotlib.backend_bases import FigureCanvasBase
    return sorted(FigureCanvasBase.get_supported_filetypes())


def plot_file(name: str, path: Path) -> Path:
    """An output file whose extension is one matplotlib writes; a path without an extension is
    refused rather than silently given ``.png``."""
    formats = plot_formats()
    listed = ", ".join(f".{f}" for f in formats)
    extension = path.suffix[1:].lower()
    if not extension:
        raise UsageError(f"{name} {path}: no file extension; expected one of {listed}")
    if extension not in formats:
        raise UsageError(f"{name} {path}: cannot plot to .{extension} files; expected one of "
                         f"{listed}")
    return output_file(name, path)


def new_bag(name: str, path: Path) -> Path:
    """A bag directory to create: it must not exist yet and its parent folder must; the one rule
    of ``drill_sim run --record`` and ``drill_sim_record -o``."""
    parent = path.absolute().parent
    if path.exists():
        raise UsageError(f"{name} {path}: cannot record there: it exists already; expected a "
                         "new name")
    if not parent.is_dir():
        raise UsageError(f"{name} {path}: cannot record there: folder {parent} does not exist; "
                         "expected a new name in an existing folder")
    return path


# ---- JSON --------------------------------------------------------------------------------------
def finite_or_none(value: object) -> object:
    """``value`` with every non-finite float (NaN, ±inf) replaced by None, recursively."""
    if isinstance(value, float):      # numpy floats are floats too
        return float(value) if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: finite_or_none(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_or_none(v) for v in value]
    return value


def json_line(value: object) -> str:
    """Strict JSON (RFC 8259): undefined quantities are ``null``, never NaN or Infinity."""
    return json.dumps(finite_or_none(value), allow_nan=False)


# ---- negative numbers ------------------------------------------------------------------------
def join_negative_values(argv: Sequence[str]) -> list[str]:
    """``--opt -1e3`` as ``--opt=-1e3`` (``-o -1e3`` as ``-o-1e3``), so that a negative number
    in any notation (``-5``, ``-1e3``, ``-inf``) is taken as the option's value: argparse alone
    takes only plain ones like ``-5`` or ``-0.5``. Stops at ``--`` and ``--ros-args``."""
    out: list[str] = []
    args = list(argv)
    i = 0
    while i < len(args):
        token = args[i]
        if token in ("--", "--ros-args"):
            return out + args[i:]
        nxt = args[i + 1] if i + 1 < len(args) else None
        if nxt is not None and _is_negative_number(nxt) and _is_bare_option(token):
            out.append(f"{token}={nxt}" if token.startswith("--") else token + nxt)
            i += 2
            continue
        out.append(token)
        i += 1
    return out


def _is_bare_option(token: str) -> bool:
    """``--name`` or ``-x``, with no value attached."""
    if token.startswith("--"):
        return len(token) > 2 and "=" not in token
    return len(token) == 2 and token[0] == "-" and token[1].isalpha()


def _is_negative_number(token: str) -> bool:
    if not token.startswith("-"):
        return False
    try:
        float(token)
    except ValueError:
        return False
    return True


SAMPLE_PERIOD_RANGE_S = (1e-4, 0.1)   # a law's sample period h [s] on the command line


def sample_period(value: object) -> float:
    """``--sample-period``: a law's sample period h [s], within SAMPLE_PERIOD_RANGE_S."""
    return in_range("--sample-period", value, *SAMPLE_PERIOD_RANGE_S, unit="s")
