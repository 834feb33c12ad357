"""The console scripts' entry points (``setup.py``; ``ros2 run`` finds the same scripts).

Importing a program (numba, rclpy, the message packages) takes a second or more. A Ctrl-C in
that time used to print a ``KeyboardInterrupt`` traceback from deep inside an import; here it
stops the program quietly with status 130. Once imported, the program's own handling of
SIGINT takes over (Python's, or the handlers of ``ros.stopping.init_stoppable``). A SIGINT
the program inherited as ignored stays ignored until then.
"""

from __future__ import annotations

import importlib
import signal
import sys


def _quiet(signum: int, frame) -> None:
    raise SystemExit(128 + signum)


def _main(module: str) -> int:
    ignored = signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    if not ignored:
        signal.signal(signal.SIGINT, _quiet)
    main = importlib.import_module(module).main
    if not ignored:
        signal.signal(signal.SIGINT, signal.default_int_handler)
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
