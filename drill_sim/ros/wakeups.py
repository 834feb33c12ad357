"""Wake-ups on time: the process's timer slack, tightened before the middleware starts, and
the real-time loop's thread under SCHED_FIFO when asked (``thread_priority``).

Linux lets a sleeping thread's timer fire up to its "timer slack" late (50 us by default) so
that wake-ups can be merged. For a 1 kHz rig that is 5 % of every period: each sleep of the
real-time loop and each timed middleware wait (an rcl wait of zero timeout took ~65 us here,
~10 us with 1 us of slack) ended that much late. Threads inherit the slack of the thread
that creates them, so it is set before rclpy starts the middleware's threads.

Under the default scheduler a waking thread may wait for another process's time slice: on a
shared 2-core machine the node's tick period p99 (median of 1 s windows) was 1.06-1.71 ms,
1.04-1.12 ms under SCHED_FIFO where the machine's own floor allowed it
(``benchmarks/bench_node.py``). ros2_control's control loop does the same (its
``thread_priority``, 50).
"""

from __future__ import annotations

import ctypes
import os
import sys

PR_SET_TIMERSLACK = 29            # linux/prctl.h
TIMER_SLACK_NS = 1000             # 1 us: a wake-up at most this much later than asked


def tighten_timer_slack(slack_ns: int = TIMER_SLACK_NS) -> bool:
    """Set this thread's timer slack [ns] (and so that of the threads it starts); False where
    the system has no such setting (not Linux), which only costs timing precision."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        return ctypes.CDLL(None, use_errno=True).prctl(PR_SET_TIMERSLACK, slack_ns, 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def run_at_priority(priority: int) -> str | None:
    """Put the calling thread under SCHED_FIFO at ``priority`` (1-99): that thread only, the
    middleware's threads and those started later keep the default scheduler. None when done,
    else why not, with what would allow it."""
    if not hasattr(os, "SCHED_FIFO"):
        return "this system has no SCHED_FIFO"
    try:
        # reset on fork: threads started from it later (rclpy's timers thread) do not inherit
        os.sched_setscheduler(0, os.SCHED_FIFO | getattr(os, "SCHED_RESET_ON_FORK", 0),
                              os.sched_param(priority))
    except PermissionError:
        return ("this user may not use SCHED_FIFO: run as root, give the program CAP_SYS_NICE, "
                "or allow it an rtprio limit (e.g. '@realtime - rtprio 98' in "
                "/etc/security/limits.conf and the user in group realtime)")
    except OSError as exc:
        return f"SCHED_FIFO {priority} refused: {exc.strerror}"
    return None
