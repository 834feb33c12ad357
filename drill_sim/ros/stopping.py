"""rclpy start-up for programs that stop between two units of work, not in the middle of one.

rclpy's own SIGINT handler raises inside whatever callback runs; the node, the recorder and
the player instead take SIGINT and SIGTERM as a request, checked at their loop's safe points,
so a tick is never published but not recorded, and a bag is always closed properly.
Every such program also wakes on time (``wakeups``: the timer slack, set before the
middleware's threads start).
"""

from __future__ import annotations

import itertools
import signal
import subprocess
import sys
from pathlib import Path

import rclpy
import rclpy.utilities
from rclpy._rclpy_pybind11 import RCLError
from rclpy.signals import SignalHandlerOptions

from .wakeups import tighten_timer_slack


def init_stoppable(args: list[str] | None, ros_args_only: bool = False) -> list[int]:
    """``rclpy.init`` without its signal handlers; the returned list gets the number of each
    SIGINT or SIGTERM received (empty: keep going). ``ros_args_only``: a program configured by
    ROS parameters alone refuses arguments outside ``--ros-args``, which ROS would ignore
    without a word (``drill_sim_node -p rate_hz:=100`` ran at 1000 Hz)."""
    tighten_timer_slack()
    name = Path(sys.argv[0]).name
    argv = sys.argv if args is None else args
    for flag, path in itertools.pairwise(argv):
        if flag == "--params-file" and not Path(path).is_file():
            what = "not a file" if Path(path).exists() else "no such file"
            print(f"{name}: cannot start ROS: --params-file {path}: {what}; expected the path "
                  "of a YAML parameters file", file=sys.stderr)
            raise SystemExit(2)
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except RCLError as exc:            # e.g. a --params-file that does not parse
        why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        print(f"{name}: cannot start ROS: {why}; expected valid --ros-args (a --params-file "
              "that exists and parses, name:=value remappings)", file=sys.stderr)
        raise SystemExit(2) from None
    if ros_args_only and (stray := rclpy.utilities.remove_ros_args(argv)[1:]):
        rclpy.try_shutdown()
        print(f"{name}: arguments outside --ros-args are not read: {' '.join(stray)}; "
              f"expected them after --ros-args ({name} --ros-args -p name:=value)",
              file=sys.stderr)
        raise SystemExit(2)
    stop: list[int] = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda signum, frame: stop.append(signum))
    return stop


def without_ros_args(argv: list[str]) -> list[str]:
    """``argv`` without its ROS arguments (``--ros-args ... --``), as rclpy parses them."""
    return rclpy.utilities.remove_ros_args(argv)


def shutdown() -> None:
    """rclpy's shutdown, if it is still up."""
    rclpy.try_shutdown()


def stop_processes(procs: list[subprocess.Popen], timeout_s: float = 10.0) -> None:
    """Ask each child still running to stop (SIGINT: it stops at its next safe point, so its
    bag is closed properly), then wait for each; one that has not ended in ``timeout_s`` [s]
    is killed."""
    for p in procs:
        if p.poll() is None:
            p.send_signal(signal.SIGINT)
    for p in procs:
        try:
            p.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            p.kill()
