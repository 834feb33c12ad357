"""``drill_sim bag repair``: rewrite the damaged files of a bag, keeping every original."""

from __future__ import annotations

import argparse
from pathlib import Path

from ...bag.repair import repair

HELP = ("rewrite a damaged or crashed bag from every intact chunk: summary, indexes, "
        "metadata.yaml (originals kept as *.damaged)")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("bag", type=Path, help="bag directory")


def run(args: argparse.Namespace) -> int:
    result = repair(args.bag)
    i = result.info
    print(f"repaired {args.bag}: {i.message_count} messages over {i.duration_s:.3f} s of log "
          "time in the bag")
    for f in result.files:
        print(f"  {f.name}: rewritten with {f.messages} messages; the original is kept as "
              f"{f.kept_as}")
        for lost in f.lost:
            print(f"    lost: {lost}")
        if not f.lost:
            print("    nothing lost (only the summary and indexes were missing)")
    if result.metadata_kept_as:
        print(f"  metadata.yaml rewritten; the old one is kept as {result.metadata_kept_as}")
    else:
        print("  metadata.yaml written")
    return 0
