"""``drill_sim bag``: tools on rosbag2 MCAP bags (any bag, not only the ones drill_sim wrote).

One module per tool, each with ``HELP``, ``add_arguments(parser)`` and ``run(args) -> int``;
argparse picks the tool. Each tool opens its bag once (``drill_sim.bag.bag.Bag``).
"""

from __future__ import annotations

import argparse

from ...bag.errors import BagError
from ...wire import WireError
from ..errors import UsageError
from . import compare, diagnostics, export, info, metrics, plot, repair, resim

HELP = ("tools on rosbag2 MCAP bags: info, repair, metrics, export, plot, compare, resim, "
        "diagnostics")
TOOLS = {"info": info, "repair": repair, "resim": resim, "metrics": metrics,
         "export": export, "plot": plot, "compare": compare, "diagnostics": diagnostics}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The tools as subcommands of ``parser`` (the ``bag`` command's own)."""
    tools = parser.add_subparsers(dest="bag_command", required=True, parser_class=type(parser))
    for name, tool in TOOLS.items():
        sub = tools.add_parser(name, help=tool.HELP)
        tool.add_arguments(sub)
        sub.set_defaults(bag_run=tool.run)


def run(args: argparse.Namespace) -> int:
    """Run the chosen tool; a bag it cannot read is a usage error (one line, status 2)."""
    try:
        return args.bag_run(args)
    except (BagError, WireError) as exc:
        raise UsageError(str(exc)) from None
