"""Wake-ups on time: the process's timer slack, tightened before the middleware starts.

Linux lets a sleeping thread's timer fire up to its "timer slack" late (50 us by default) so
that wake-ups can be merged. For a 1 kHz rig that is 5 % of every period: each sleep of the
real-time loop and each timed middleware wait (an rcl wait of zero timeout took ~65 us here,
~10 us with 1 us of slack) ended that much late. Threads inherit the slack of the thread
that creates them, so it is set before rclpy starts the middleware's threads.
"""

from __future__ import annotations

import ctypes
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
