"""rclpy start-up for programs that stop between two units of work, not in the middle of one.

rclpy's own SIGINT handler raises inside whatever callback runs; the node, the recorder and
the player instead take SIGINT and SIGTERM as a request, checked at their loop's safe points,
so a tick is never published but not recorded, and a bag is always closed properly.
"""

from __future__ import annotations

import signal

import rclpy
from rclpy.signals import SignalHandlerOptions


def init_stoppable(args: list[str] | None) -> list[int]:
    """``rclpy.init`` without its signal handlers; the returned list gets the number of each
    SIGINT or SIGTERM received (empty: keep going)."""
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    stop: list[int] = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda signum, frame: stop.append(signum))
    return stop
