"""This machine's own wake-up floor at 1 kHz: what any real-time program here can do at best.

A process that does nothing but sleep until the next 1 ms of an absolute grid (as the rig
node's real-time loop does: 1 us of timer slack, no work) for --seconds, and how late it woke:
the share of wake-ups more than half a period late (the node's rounding would advance two
ticks there), the p99 of the period between wake-ups, the latest wake-up, the share more than
50 us late and the median lateness (what waking a sleeping core costs). A rig node cannot
hold its targets (>= 99.5 % of ticks on time, p99 period <= 1.2 ms) on a machine whose floor
misses them: compare `bench_node.py` with this, run beside it (it prints this first).

--fifo PRIORITY sleeps under SCHED_FIFO at that priority (root or CAP_SYS_NICE; on a real-time
kernel this is the figure that counts). --cpu-wakeup-latency-us N holds the kernel's CPU
latency request at N us while it measures (as the node's cpu_wakeup_latency_us; 0: idle cores
poll; root).

Run: .venv/bin/python benchmarks/bench_wakeups.py [--seconds 15] [--fifo 50]
         [--cpu-wakeup-latency-us 0]
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import dataclass

import numpy as np

from drill_sim.ros.wakeups import CpuLatencyRequest, tighten_timer_slack

PERIOD_S = 1e-3


@dataclass(frozen=True)
class Floor:
    """How late a do-nothing 1 kHz sleeper woke up."""

    wakeups: int
    late_half_period: float       # share of wake-ups more than half a period late
    period_p99_ms: float
    latest_ms: float              # the latest wake-up, after its deadline [ms]
    late_50us: float = 0.0        # share of wake-ups more than 50 us late
    late_median_us: float = 0.0   # the median wake-up's lateness [us]

    def line(self, seconds: float, how: str = "") -> str:
        return (f"this machine's floor{how}, a do-nothing 1 kHz sleeper for {seconds:g} s: "
                f"{100 * (1 - self.late_half_period):.2f} % of wake-ups within half a period, "
                f"period p99 {self.period_p99_ms:.3f} ms, latest {self.latest_ms:.2f} ms late; "
                f"{100 * self.late_50us:.1f} % more than 50 us late, median "
                f"{self.late_median_us:.0f} us late")


def floor(seconds: float, fifo: int = 0) -> Floor:
    """Sleep to a 1 ms grid for ``seconds`` [s] in this process (SCHED_FIFO at ``fifo`` if
    > 0, for the time of the measurement only) and measure how late each wake-up came."""
    tighten_timer_slack()
    before = os.sched_getscheduler(0), os.sched_getparam(0)
    if fifo:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(fifo))
    try:
        n = int(seconds / PERIOD_S)
        woke = np.empty(n)
        start = time.monotonic() + PERIOD_S
        for k in range(n):
            pause = start + k * PERIOD_S - time.monotonic()
            if pause > 0:
                time.sleep(pause)
            woke[k] = time.monotonic()
    finally:
        if fifo:
            os.sched_setscheduler(0, *before)
    late = woke - (start + np.arange(n) * PERIOD_S)
    return Floor(n, float(np.mean(late > PERIOD_S / 2)),
                 float(np.percentile(np.diff(woke), 99) * 1e3), float(late.max() * 1e3),
                 float(np.mean(late > 50e-6)), float(np.median(late) * 1e6))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=15.0)
    parser.add_argument("--fifo", type=int, default=0, metavar="PRIORITY",
                        help="sleep under SCHED_FIFO at this priority (1-99)")
    parser.add_argument("--cpu-wakeup-latency-us", type=int, default=-1, metavar="US",
                        help="hold the CPU latency request at this while measuring (0: idle "
                        "cores poll)")
    args = parser.parse_args()
    how = [f"SCHED_FIFO {args.fifo}"] if args.fifo else []
    request = None
    if args.cpu_wakeup_latency_us >= 0:
        request = CpuLatencyRequest(args.cpu_wakeup_latency_us)
        if not request.held:
            raise SystemExit(f"--cpu-wakeup-latency-us: {request.refused}")
        how.append(f"idle cores held to {args.cpu_wakeup_latency_us} us wake-ups")
    try:
        f = floor(args.seconds, args.fifo)
    except PermissionError:
        raise SystemExit("--fifo: this user may not use SCHED_FIFO (needs root, CAP_SYS_NICE "
                         "or an rtprio limit)") from None
    finally:
        if request is not None:
            request.close()
    print(f.line(args.seconds, f" ({', '.join(how)})" if how else ""))


if __name__ == "__main__":
    main()
