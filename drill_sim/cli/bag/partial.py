"""What the reading tools share about damage: the ``--partial`` option, and the verdict on a
result whose bag had problems (data lost: the result covers only part of the bag) or notes
(odd, but nothing lost)."""

from __future__ import annotations

import argparse
import sys

from ...bag.bag import Bag

PARTIAL_EXIT = 1          # a result over part of a damaged bag, not accepted with --partial


def add_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--partial", action="store_true",
                        help="accept a result over the readable part of a damaged bag "
                             "(exit 0; without it such a result is refused with exit 1)")


def known(bag: Bag) -> tuple[list[str], list[str]]:
    """(problems, notes) the bag is known for before it is read: what earlier repairs lost,
    files listed twice, a missing metadata.yaml."""
    problems, notes = bag.repaired()
    return problems, notes + bag.notes


def verdict(problems: list[str], notes: list[str], partial: bool, prog: str = "drill_sim"
            ) -> int:
    """Print the problems and notes on stderr, each once; the exit status: 0 for a sound bag
    or with ``partial``, else ``PARTIAL_EXIT`` with how to accept the partial result."""
    for note in dict.fromkeys(notes):
        print(f"{prog}: note: {note}", file=sys.stderr)
    for problem in dict.fromkeys(problems):
        print(f"{prog}: incomplete bag: {problem}", file=sys.stderr)
    if problems and not partial:
        print(f"{prog}: the result would cover only the readable part of the bag: refused "
              "(pass --partial to accept it)", file=sys.stderr)
        return PARTIAL_EXIT
    return 0
