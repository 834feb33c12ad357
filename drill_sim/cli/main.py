"""``drill_sim``: the rig with a controller, controller scores, simulations, maps, bags.

One module per command, each with ``add_arguments(parser)`` and ``run(args) -> int``, wired here
as subcommands. Bad arguments exit with status 2 and one line on stderr.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

from ..core import ParameterError
from . import bag, control, map, run, simulate, stability, tune
from .checks import join_negative_values
from .errors import Parser, UsageError

# name -> (module, help); the order is the order ``--help`` lists them in
COMMANDS = {
    "simulate": (simulate, "run the model offline and summarise it"),
    "run": (run, "the main job: rig node + scenario driver, live status, summary and plot"),
    "bag": (bag, "tools on rosbag2 MCAP bags: info, repair, metrics, export, plot, resim"),
    "stability": (stability, "steady drilling and the rightmost roots of Delta(s)"),
    "control": (control, "score the reference stick-slip controllers (or yours) on a scenario "
                         "set"),
    "map": (map, "stick-slip maps over rpm and WOB (or any two quantities), on every core or a "
                 "Dask cluster"),
    "tune": (tune, "tune a law's gains on a scenario set (Bayesian optimisation), write a "
                   "controller params file"),
}


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="drill_sim", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    for name, (module, text) in COMMANDS.items():
        module.add_arguments(sub.add_parser(name, help=text))
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(join_negative_values(sys.argv[1:] if argv is None else argv))
        return COMMANDS[args.command][0].run(args)
    except (UsageError, ParameterError) as exc:
        print(f"drill_sim: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:      # whoever read stdout has gone (``| head``): stop quietly
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:
        print(f"drill_sim: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("drill_sim: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
