"""``drill_sim_drive``: plays a driller scenario onto the rig's command topics, or holds one
speed and weight on bit (``drill_sim_drive hold --rpm 60 --wob-kn 100``). The node that plays
it: ``drill_sim.ros.driver``."""

from __future__ import annotations

import argparse
import sys

from ..core import ParameterError
from ..session.scenario import HOLD, Scenario, hold_scenario, load_scenario, scenario_names
from ..wire import rig_topics
from ..wire.qos import RELIABILITIES


def _scenario(args: argparse.Namespace) -> Scenario:
    """The scenario the arguments name (ParameterError or ValueError if they do not hold)."""
    given = [f"--{k.replace('_', '-')}" for k in ("rpm", "wob_kn", "hook_load_kn", "duration")
             if getattr(args, k) is not None]
    if args.scenario != HOLD:
        if given:
            raise ValueError(f"{', '.join(given)}: only with the hold scenario "
                             "(drill_sim_drive hold --rpm 60 --wob-kn 100)")
        return load_scenario(args.scenario)
    if args.rpm is None or (args.wob_kn is None) == (args.hook_load_kn is None):
        raise ValueError("hold needs --rpm and one of --wob-kn or --hook-load-kn")
    return hold_scenario(args.rpm, args.wob_kn, args.hook_load_kn, args.duration)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv if argv is None else argv
    parser = argparse.ArgumentParser(prog="drill_sim_drive", description=__doc__.split("\n")[0])
    parser.add_argument("scenario", nargs="?", default="tag_bottom",
                        help=f"shipped ({', '.join(scenario_names())}), a scenario YAML file, "
                             "or hold (with --rpm and --wob-kn or --hook-load-kn)")
    parser.add_argument("--rig", default=rig_topics.NODE_NAME, help="name of the rig node")
    parser.add_argument("--rate-hz", type=float, default=50.0, help="command rate [Hz]")
    parser.add_argument("--loop", action="store_true", help="repeat the scenario")
    parser.add_argument("--qos-reliability", choices=RELIABILITIES, default=RELIABILITIES[0])
    parser.add_argument("--controller", default="drill_sim_controller",
                        help="the controller node a scenario's controller section switches on")
    hold = parser.add_argument_group("hold: a constant speed and weight")
    hold.add_argument("--rpm", type=float, help="top-drive speed [rpm]")
    hold.add_argument("--wob-kn", type=float, help="weight on bit W0 = W_s - H0 [kN]")
    hold.add_argument("--hook-load-kn", type=float, help="hook load H0 [kN]")
    hold.add_argument("--duration", type=float, help="seconds to hold (default: until stopped)")
    from ..ros.stopping import without_ros_args
    args = parser.parse_args(without_ros_args(argv)[1:])
    if not 0 < args.rate_hz <= 1000:
        parser.error(f"--rate-hz = {args.rate_hz:g}: expected 0 < rate <= 1000")
    try:
        scenario = _scenario(args)
    except (ParameterError, ValueError) as exc:
        parser.error(str(exc))
    from ..ros.driver import drive
    return drive(scenario, argv, rig=args.rig, rate_hz=args.rate_hz, loop=args.loop,
                 reliability=args.qos_reliability, controller=args.controller)


if __name__ == "__main__":
    sys.exit(main())
