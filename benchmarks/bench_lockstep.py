"""Wall time per lockstep tick with one closed-loop controller in another process [issue
target: at most 0.3 ms a tick].

A rig node in lockstep (``publish_clock``, ``lockstep``, ``start_paused``, 1000 Hz) runs in one
process; a PI controller on ``~/bit/twist`` answering on ``~/cmd/top_drive`` runs in another,
resumes the rig and answers --ticks samples. The controller is, by default, the lean one
(``lean_controller.py``: raw CDR bytes in and out, an rcl wait set, no executor), since the
figure is meant to be the rig's cost and any controller may be written so; ``--controller
rclpy`` runs the test suite's plain-rclpy PI (``tests/ros/lockstep_controller.py``, message
objects, an executor) instead. The controller times its first to its last answer; the figure
is that over the ticks, with the CPU both processes used per tick.

Measured on 2 shared cores (load average from the other jobs): lean, 0.31-0.33 ms a tick at
load 1.7, 0.33-0.35 ms at 2.1, 0.35-0.39 ms at 2.5-4 (CPU 0.21-0.25 ms node + 0.12-0.16 ms
controller); the rclpy controller 0.40-0.42 ms at load 2.1. On a slower machine (load
0.3-1.3), with the node's timer slack at 1 us: lean 0.27-0.31 ms, --best-effort 0.20-0.26 ms,
--rig floor 0.18-0.20 ms. The machine's other load enters the figure: say how loaded it was.

``--rig floor`` puts ``floor_rig.py`` in the rig's place: it publishes a sample and waits for
its answer, nothing else, so its figure is the middleware's floor on this machine (the rig's
own share of a tick is the difference).

``--best-effort``: the rig with ``qos_reliability:=best_effort`` and the lean controller (and
floor rig) best effort too: no acknowledgements or heartbeats on either side.

``--thread-priority N``: the node with ``thread_priority:=N`` (its loop under SCHED_FIFO) and
the controller under ``chrt -f N``.

``--cpu-wakeup-latency-us N``: the node with ``cpu_wakeup_latency_us:=N`` (no idle core sleeps
deeper than N us while it runs; 0: they poll, so neither process waits for its core to wake);
with ``--rig floor`` the benchmark holds that request itself.

Run: .venv/bin/python benchmarks/bench_lockstep.py [--ticks 5000] [--record] [--repeat 3]
         [--controller lean|rclpy] [--executor waitset|events|single] [--rig node|floor]
         [--best-effort] [--thread-priority 50] [--cpu-wakeup-latency-us 0]
         (--executor: the lean controller's wait, or the rclpy controller's executor)
"""

from __future__ import annotations

import argparse
import os
import random
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

from drill_sim.ros.wakeups import CpuLatencyRequest

BIN = Path(sys.executable).parent
CONTROLLERS = {"lean": Path(__file__).resolve().parent / "lean_controller.py",
               "rclpy": Path(__file__).resolve().parents[1] / "tests" / "ros"
               / "lockstep_controller.py"}
NS = "/bench_lockstep"


def _cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def run_once(ticks: int, record: Path | None, controller: str,
             executor: str, rig: str = "node",
             best_effort: bool = False, priority: int = 0,
             latency_us: int = -1) -> tuple[float, float, float]:
    """(wall ms, node CPU ms, controller CPU ms) per lockstep tick."""
    qos = ["--best-effort"] if best_effort else []
    if rig == "floor":
        args = [sys.executable, str(Path(__file__).resolve().parent / "floor_rig.py"),
                "--rig", f"{NS}/drill_sim", *qos]
    else:
        args = [str(BIN / "drill_sim_node"), "--ros-args", "-r", f"__ns:={NS}",
                "-p", "publish_clock:=true", "-p", "lockstep:=true", "-p", "start_paused:=true",
                "-p", f"qos_reliability:={'best_effort' if best_effort else 'reliable'}"]
    if record is not None:
        args += ["-p", f"record:={record}"]
    if priority and rig == "node":
        args += ["-p", f"thread_priority:={priority}"]
    if latency_us >= 0 and rig == "node":
        args += ["-p", f"cpu_wakeup_latency_us:={latency_us}"]
    chrt = ["chrt", "-f", str(priority)] if priority else []
    node = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        how = ["--executor", executor] if controller == "rclpy" else ["--wait", executor]
        ctl = subprocess.Popen([*chrt, sys.executable, str(CONTROLLERS[controller]), "--rig",
                                f"{NS}/drill_sim", "--ticks", str(ticks), "--resume", *how,
                                *qos],
                               stdout=subprocess.PIPE,
                               text=True)
        cpu_node0 = None
        for line in ctl.stdout:
            if line.startswith("connected"):
                cpu_node0, cpu_ctl0 = _cpu_s(node.pid), _cpu_s(ctl.pid)
            if line.startswith("answered"):
                cpu_node, cpu_ctl = _cpu_s(node.pid), _cpu_s(ctl.pid)
                wall_s = float(line.split(" in ")[1].split()[0])
                break
        else:
            raise SystemExit("the controller stopped before answering every tick")
        ctl.wait(timeout=30)
    finally:
        node.send_signal(signal.SIGINT)
        node.wait(timeout=30)
    per = 1e3 / ticks
    return wall_s * per, (cpu_node - cpu_node0) * per, (cpu_ctl - cpu_ctl0) * per


def latency_note(latency_us: int) -> str:
    return f", idle cores held to {latency_us} us wake-ups" if latency_us >= 0 else ""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--ticks", type=int, default=5000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--record", action="store_true", help="the node records its bag too")
    parser.add_argument("--controller", choices=tuple(CONTROLLERS), default="lean")
    parser.add_argument("--rig", choices=("node", "floor"), default="node",
                        help="floor: a rig that only publishes and waits (floor_rig.py)")
    parser.add_argument("--executor", choices=("events", "single", "waitset"), default=None,
                        help="rclpy: its executor (events, default; single); lean: its wait "
                        "(waitset, default; events)")
    parser.add_argument("--best-effort", action="store_true",
                        help="the rig with qos_reliability:=best_effort, the lean controller "
                        "and the floor rig best effort too")
    parser.add_argument("--thread-priority", type=int, default=0, metavar="PRIORITY",
                        help="the node's thread_priority (its loop under SCHED_FIFO) and the "
                        "controller under chrt -f PRIORITY")
    parser.add_argument("--cpu-wakeup-latency-us", type=int, default=-1, metavar="US",
                        help="the node's cpu_wakeup_latency_us (0: idle cores poll while it "
                        "runs; needs root); with --rig floor held by the benchmark")
    args = parser.parse_args()
    args.executor = args.executor or ("waitset" if args.controller == "lean" else "events")
    if args.rig == "floor" and (args.record or args.controller != "lean"):
        parser.error("--rig floor takes the lean controller and no --record")
    if args.best_effort and args.controller != "lean":
        parser.error("--best-effort takes the lean controller")
    os.environ.setdefault("ROS_DOMAIN_ID", str(random.randint(150, 230)))
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    print(f"lockstep, 1000 Hz, one PI controller in another process, {args.ticks} ticks"
          f"{', recording' if args.record else ''}"
          f"{f', SCHED_FIFO {args.thread_priority}' if args.thread_priority else ''}"
          f"{latency_note(args.cpu_wakeup_latency_us)}"
          f", rig {args.rig}, controller {args.controller} "
          f"({args.executor}), {'best effort' if args.best_effort else 'reliable'}; "
          "load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    request = (CpuLatencyRequest(args.cpu_wakeup_latency_us)
               if args.rig == "floor" and args.cpu_wakeup_latency_us >= 0 else None)
    if request is not None and not request.held:
        raise SystemExit(f"--cpu-wakeup-latency-us: {request.refused}")
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.repeat):
            bag = Path(tmp) / f"run{k}" if args.record else None
            wall, node_cpu, ctl_cpu = run_once(args.ticks, bag, args.controller, args.executor,
                                               args.rig, args.best_effort,
                                               args.thread_priority,
                                               args.cpu_wakeup_latency_us)
            print(f"run {k + 1}: {wall:.3f} ms wall a tick (target <= 0.3 ms), CPU "
                  f"{node_cpu:.3f} ms node + {ctl_cpu:.3f} ms controller a tick; "
                  f"{1.0 / wall:.2f} x real time")


if __name__ == "__main__":
    main()
