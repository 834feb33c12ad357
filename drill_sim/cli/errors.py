"""The one error type of the command line: a bad argument, reported on one line, status 2."""

from __future__ import annotations

import argparse


class UsageError(Exception):
    """A bad command-line argument: reported on one line, exit status 2."""


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are UsageError: one clear line, never a usage dump."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise UsageError(message)
