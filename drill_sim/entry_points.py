"""The console scripts' entry points (``setup.py``; ``ros2 run`` finds the same scripts).

Importing a program (numba, rclpy, the message packages) takes a second or more. A Ctrl-C or a
SIGTERM in that time used to print a ``KeyboardInterrupt`` traceback from deep inside an
import, or, to a program started in the background by a shell (SIGINT inherited as ignored),
was lost and the program ran on; here either stops the program quietly, with status 128 + the
signal's number, whatever it inherited. Once imported, the program's own handling takes over:
SIGINT is Python's KeyboardInterrupt (the ROS programs then take SIGINT and SIGTERM as a
request to stop between two units of work, ``ros.stopping.init_stoppable``), SIGTERM as it was.
"""

from __future__ import annotations

import importlib
import signal
import sys

_SIGNALLED: list[int] = []       # signals that came while importing


def _quiet(signum: int, frame) -> None:
    _SIGNALLED.append(signum)
    raise SystemExit(128 + signum)


def _main(module: str) -> int:
    term = signal.getsignal(signal.SIGTERM)
    for sig in (signal.SIGINT, signal.SIGTERM):      # whatever was inherited, even SIG_IGN
        signal.signal(sig, _quiet)
    main = importlib.import_module(module).main
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, term)
    if _SIGNALLED:      # an import swallowed the SystemExit (``except BaseException``): stop
        return 128 + _SIGNALLED[0]
    return main()


def drill_sim() -> int:
    return _main("drill_sim.cli.main")


def node() -> int:
    return _main("drill_sim.ros.node")


def drive() -> int:
    return _main("drill_sim.cli.drive")


def controller() -> int:
    return _main("drill_sim.ros.controller")


def record() -> int:
    return _main("drill_sim.cli.record")


def replay() -> int:
    return _main("drill_sim.cli.replay")


if __name__ == "__main__":
    sys.exit(drill_sim())
