"""``drill_sim bag repair``: rewrite a bag cut short by a crash."""

from __future__ import annotations

import argparse
from pathlib import Path

from ...bag.repair import repair

HELP = "rewrite a bag cut short by a crash: summary, indexes, metadata.yaml (originals kept)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("bag", type=Path, help="bag directory")


def run(args: argparse.Namespace) -> int:
    result = repair(args.bag)
    print(f"repaired {args.bag}: {result.message_count} messages over "
          f"{result.duration_s:.3f} s kept; damaged originals left as *.mcap.damaged")
    return 0
