"""``drill_sim bag metrics``: SSI, stick fraction and means of a recorded rig session."""

from __future__ import annotations

import argparse
import json

from . import window

HELP = "SSI, stick fraction and means of a recorded rig session"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    window.add_arguments(parser)
    parser.add_argument("--json", action="store_true", help="one JSON object on stdout")


def run(args: argparse.Namespace) -> int:
    window.check(args)
    s = window.series(args)
    m = s.metrics()
    if args.json:
        print(json.dumps(m))
        return 0
    print(f"{s.topic}: {m['samples']} samples over {m['duration_s']:.3f} s")
    for key, value in m.items():
        if key not in ("samples", "duration_s"):
            print(f"  {key:<24} {value:.6g}")
    return 0
