"""What ``metrics``, ``export`` and ``plot`` share: the bag, the rig's topic, the time window
(``--start``/``--end`` after the first sample, or ``--last``; the whole session by default)
and ``--partial``; the rig's samples streamed a chunk at a time, cut to the window."""

from __future__ import annotations

import argparse
import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from ...bag.bag import Bag
from ...bag.rig_stats import Window, Windowed
from ...bag.series import joint_chunks, joint_topic
from ...bag.stamped_series import MOTOR, StampedTopic, StampMatched, matched
from ..errors import UsageError
from . import partial


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("bag", type=Path, help="bag directory or .mcap file")
    parser.add_argument("--topic", help="the rig's joint_states topic, if the bag has several")
    parser.add_argument("--start", type=float,
                        help="window start [s] after the first sample (default: the first)")
    parser.add_argument("--end", type=float,
                        help="window end [s] after the first sample (default: the last)")
    parser.add_argument("--last", type=float, metavar="SECONDS",
                        help="window: the last SECONDS of header stamps, up to the latest "
                             "(instead of --start/--end; default: the whole session)")
    partial.add_argument(parser)


def check(args: argparse.Namespace, out: Path | None = None) -> None:
    """Refuse a bad window or an output in a missing folder before reading anything."""
    for name in ("start", "end"):
        value = getattr(args, name)
        if value is not None and not (math.isfinite(value) and value >= 0):
            raise UsageError(f"--{name} = {value}: expected a time >= 0 s")
    if args.start is not None and args.end is not None and args.end <= args.start:
        raise UsageError(f"--start {args.start:g} --end {args.end:g}: the window ends before "
                         "it starts; expected --end after --start")
    if args.last is not None:
        if not (math.isfinite(args.last) and args.last > 0):
            raise UsageError(f"--last = {args.last}: expected a time > 0 s")
        if args.start is not None or args.end is not None:
            raise UsageError("--last cannot be combined with --start or --end")
    if out is not None and not out.parent.exists():
        raise UsageError(f"cannot write {out}: folder {out.parent} does not exist")


@dataclass
class Samples:
    """The rig's samples in the window (iterate ``chunks``: stamps [ns], (N, 12) values),
    its topic, and what was found wrong with the bag on the way (``problems``, ``notes``)."""

    topic: str
    chunks: Windowed
    bag: Bag
    problems: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    # the rig's stamped topics beside (motor torque, measured quantities), matched by stamp
    stamped: list[tuple[StampedTopic, StampMatched]] = field(default_factory=list)

    @property
    def motor(self) -> StampMatched | None:
        """The motor torque [N m] at the chunks' stamps (one column), if the bag has it."""
        return next((m for spec, m in self.stamped if spec is MOTOR), None)

    def verdict(self, args: argparse.Namespace, more: list[str] = ()) -> int:
        """``partial.verdict`` on what was found (call once the chunks are read)."""
        return partial.verdict(self.problems + list(more), self.notes, args.partial)


@contextmanager
def samples(args: argparse.Namespace) -> Iterator[Samples]:
    """The bag opened, its rig's samples in the window ready to stream."""
    with Bag.open(args.bag) as bag:
        name = joint_topic(bag, args.topic)
        problems, notes = partial.known(bag)
        window = Window(args.start, args.end, args.last)
        yield Samples(name, Windowed(joint_chunks(bag, name, problems), window), bag,
                      problems, notes, matched(bag, name))
