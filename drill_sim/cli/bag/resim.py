"""``drill_sim bag resim``: run the model again from a session's bag and compare; exit status
1 when the re-run differs from the recording or the bag is incomplete (with ``--partial``, 0
when every sample read matched)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ...bag.bag import Bag
from ...session.resim import ResimResult, resimulate
from ...terminal import Progress
from . import partial

HELP = ("run the model again from the recorded parameters and commands and compare with the "
        "recorded outputs (exit 1 if they differ)")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("bag", type=Path, help="bag directory or .mcap file of a rig session")
    parser.add_argument("--json", action="store_true", help="one JSON object on stdout")
    partial.add_argument(parser)


def run(args: argparse.Namespace) -> int:
    progress = Progress("re-simulating")
    try:
        with Bag.open(args.bag) as bag:
            r = resimulate(bag, progress)
    finally:
        progress.close()
    if args.json:
        print(json.dumps(_as_json(r)))
    else:
        _print(r)
    return 0 if r.exact or (args.partial and r.matched) else 1


def _as_json(r: ResimResult) -> dict:
    return {"bag": str(r.bag), "mode": r.mode, "preset": r.preset, "samples": r.samples,
            "commands": r.commands, "refused": r.refused, "events": r.events,
            "exact": r.exact, "matched": r.matched, "problems": r.problems,
            "max_difference": r.max_difference,
            "worst": dict(zip(("quantity", "difference", "time_s"), r.worst, strict=True)),
            "explanation": r.explanation()}


def _print(r: ResimResult) -> None:
    print(f"{r.bag}: {r.mode} session (preset {r.preset}), {r.samples} samples, "
          f"{r.commands} commands used, {r.refused} refused, "
          f"{r.events.count('reset')} resets, {r.events.count('parameters')} parameter changes")
    print("largest difference re-run - recorded, per quantity:")
    for name, value in r.max_difference.items():
        print(f"  {name:<24} {value:.3g}")
    if not r.matched:
        name, value, t = r.worst
        print(f"worst: {name} off by {value:.3g} at t = {t:.6f} s")
    print(r.explanation())
