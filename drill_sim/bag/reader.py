"""One-shot reading of a bag by its path, for scripts and tests: each call opens the bag once
(``bag.Bag``) and closes it again. A tool that asks a bag more than one thing holds a ``Bag``
instead, so its files are opened once."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

from .bag import Bag, BagInfo, BagMessage, TopicInfo
from .repair import repair as repair_bag

__all__ = ["BagInfo", "BagMessage", "TopicInfo", "info", "read_messages", "repair"]


def info(path: str | Path) -> BagInfo:
    """``Bag.info`` of the bag at ``path``."""
    with Bag.open(path) as bag:
        return bag.info()


def read_messages(path: str | Path, topics: set[str] | None = None,
                  problems: list[str] | None = None) -> Iterator[BagMessage]:
    """``Bag.messages`` of the bag at ``path``: every readable message in file order."""
    with Bag.open(path) as bag:
        yield from bag.messages(topics, problems)



def repair(path: str | Path) -> BagInfo:
    """``repair.repair`` of the bag at ``path``: the info of the repaired bag."""
    return repair_bag(path).info
