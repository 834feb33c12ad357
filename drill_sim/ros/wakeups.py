"""Wake-ups on time: the process's timer slack, tightened before the middleware starts; the
real-time loop's thread under SCHED_FIFO when asked (``thread_priority``); and idle cores kept
out of deep sleep while the node runs when asked (``cpu_wakeup_latency_us``).

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
import struct
import sys

PR_SET_TIMERSLACK = 29            # linux/prctl.h
TIMER_SLACK_NS = 1000             # 1 us: a wake-up at most this much later than asked
CPU_LATENCY_DEVICE = "/dev/cpu_dma_latency"      # Linux's CPU latency QoS request


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


class CpuLatencyRequest:
    """A request to the kernel's CPU latency QoS (``/dev/cpu_dma_latency``): no core may sleep
    in an idle state whose exit takes longer than the latency asked, for as long as the
    request is open; 0: idle cores poll. A waking thread then finds its core awake: on a
    2-core virtual machine the share of 1 kHz wake-ups more than 50 us late went from 58-74 %
    to 1.4-4.2 % (``benchmarks/bench_wakeups.py``). It is the kernel's interface for this (the one
    ``cyclictest`` holds) and it applies to the whole machine (idle cores then cost power),
    so the node takes it only when asked. The kernel drops the request when the file closes,
    also when the process dies: nothing stays behind on the machine."""

    def __init__(self, latency_us: int, device: str = CPU_LATENCY_DEVICE) -> None:
        """Open the request; ``refused`` says why not (with what would allow it), else None."""
        self.latency_us, self._fd, self.refused = latency_us, -1, None
        try:
            self._fd = os.open(device, os.O_WRONLY | getattr(os, "O_CLOEXEC", 0))
            os.write(self._fd, struct.pack("=i", latency_us))
        except FileNotFoundError:
            self.refused = f"this system has no {device} (Linux's CPU latency QoS)"
        except PermissionError:
            self.refused = (f"this user may not write {device}: run as root, or give the "
                            "user write access to it (a udev rule)")
        except OSError as exc:
            self.refused = f"{device} refused {latency_us} us: {exc.strerror}"
        if self.refused is not None:
            self.close()

    @property
    def held(self) -> bool:
        return self._fd >= 0

    def close(self) -> None:
        """Withdraw the request (idempotent)."""
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1


def cpu_latency_now_us(device: str = CPU_LATENCY_DEVICE) -> int | None:
    """The machine's CPU latency limit in force [us] (the least of all requests; 2e9 with
    none), or None where it cannot be read (root only)."""
    try:
        with open(device, "rb") as f:
            return struct.unpack("=i", f.read(4))[0]
    except (OSError, struct.error):
        return None


def take_thread_priority(p: dict, max_speed: bool, logger) -> None:
    """``thread_priority`` > 0: this (the loop's) thread under SCHED_FIFO, in real time and
    lockstep; not at max speed (``max_speed``: the loop never sleeps), where it would starve
    the machine's other programs. Refused, the rig runs on and says why (``logger``)."""
    priority = int(p["thread_priority"])
    if not priority:
        return
    if max_speed:
        logger.info(f"thread_priority {priority} not taken at max speed (its loop never "
                    "sleeps: under SCHED_FIFO it would starve the machine's other programs)")
        return
    refused = run_at_priority(priority)
    if refused is None:
        logger.info(f"ticking under SCHED_FIFO, priority {priority}")
    else:
        logger.warning(f"thread_priority {priority} not taken: {refused}; ticking under the "
                       "default scheduler")


def request_cpu_latency(p: dict, logger) -> CpuLatencyRequest | None:
    """``cpu_wakeup_latency_us`` >= 0: the request held open for the node's life (closed at
    shutdown, or by the kernel if the process dies). Refused, the rig runs on and says why."""
    latency_us = int(p["cpu_wakeup_latency_us"])
    if latency_us < 0:
        return None
    request = CpuLatencyRequest(latency_us)
    if request.held:
        logger.info(f"idle cores held to wake-ups of at most {latency_us} us while the node "
                    "runs (the whole machine's setting)")
    else:
        logger.warning(f"cpu_wakeup_latency_us {latency_us} not taken: {request.refused}; "
                       "idle cores sleep as the machine sets")
    return request
