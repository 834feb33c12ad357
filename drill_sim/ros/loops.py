"""The rig node's three run loops, one policy each (as ros2_control's controller manager keeps
its sleeping policies): real time (ticks when the pacer says they are due, sleeping between),
max speed (ticks back to back) and lockstep (a tick when every lockstep topic has answered the
last one, blocked in the middleware meanwhile). Each serves the executor (services,
parameters, diagnostics) between its ticks with ``spin_once``.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Protocol

from rclpy.experimental import EventsExecutor

from ..session.rig_session import RigSession
from .commands import CommandInbox


class RigNode(Protocol):
    """What a loop needs of the rig node (``drill_sim.ros.node.RigNode``)."""

    session: RigSession
    commands: CommandInbox
    send: Sequence[Callable[[bytes], object]]

    def tick(self) -> None: ...
    def serve(self, executor: EventsExecutor) -> None: ...
    def take_commands(self) -> None: ...
    def lockstep_overdue(self, now: float) -> None: ...


SERVE_PERIOD_S = 1e-3        # max speed: services, parameters, diagnostics served this often
# real time: served this often [s]. The ticks are paced by the node's own sleep, not by an
# executor timer: dispatching a 1 kHz timer through the executor cost ~7 % of a core more.
REAL_TIME_SERVE_PERIOD_S = 5e-3
# lockstep: served this often [s] (a spin of the executor costs ~0.1 ms, a third of a tick)
LOCKSTEP_SERVE_PERIOD_S = 0.02


def run(node: RigNode, executor: EventsExecutor, stop: list[int]) -> None:
    """The loop the node's parameters choose, until ``stop`` gets a signal."""
    if node.session.lockstep is not None:
        run_lockstep(node, executor, stop)
    elif node.session.pacer.max_speed:
        run_max_speed(node, executor, stop)
    else:
        run_real_time(node, executor, stop)


def run_max_speed(node: RigNode, executor: EventsExecutor, stop: list[int]) -> None:
    """Ticks back to back, each taking the commands that came; services, parameters and
    diagnostics once per wall millisecond; paused, a tick per wall millisecond."""
    next_spin = 0.0
    session = node.session
    while not stop:
        node.tick()
        now = time.monotonic()
        if session.paused:
            executor.spin_once(timeout_sec=1e-3)
        elif now >= next_spin:
            node.serve(executor)
            next_spin = now + SERVE_PERIOD_S


def run_real_time(node: RigNode, executor: EventsExecutor, stop: list[int]) -> None:
    """A tick when the pacer says the next is due (``Pacer.next_tick_s``: at factor 1 every
    1/``rate_hz`` of wall time, in phase with its grid, so each wake-up advances one tick and
    a late one costs no simulated time), sleeping in between; paused, a tick (commands taken)
    every 1/``rate_hz``; services, parameters and the diagnostics timer are served every
    REAL_TIME_SERVE_PERIOD_S."""
    pacer, session = node.session.pacer, node.session
    next_tick = next_serve = time.monotonic()
    while not stop:
        now = time.monotonic()
        if now >= next_tick:
            node.tick()
            next_tick = (now + 1.0 / pacer.rate_hz if session.paused else pacer.next_tick_s())
        if now >= next_serve:
            executor.spin_once(timeout_sec=0.0)
            next_serve = now + REAL_TIME_SERVE_PERIOD_S
        pause = min(next_tick, next_serve) - time.monotonic()
        if pause > 0.0:
            time.sleep(pause)


def run_lockstep(node: RigNode, executor: EventsExecutor, stop: list[int]) -> None:
    """Publish a tick, wait for a command stamped with its time on every lockstep topic
    (blocked in the middleware: no CPU spent), advance one tick, and so on; services,
    parameters and diagnostics are served every LOCKSTEP_SERVE_PERIOD_S and while paused.

    Per tick one wait, then one take (right after publishing nothing can have answered yet),
    and the wait watches only the lockstep topics: with Fast DDS a wait costs ~25 us of CPU
    plus ~3 us per topic watched, and only lockstep topics release a tick. Other commands are
    still taken with each tick's; while the rig waits they are taken at the latest every
    LOCKSTEP_SERVE_PERIOD_S."""
    session = node.session
    ls = session.lockstep
    watched = ls.topics
    node.commands.wait_on(watched)
    next_serve = 0.0
    while not stop:
        if ls.topics is not watched:         # the drive's mode moved its lockstep topic
            watched = ls.topics
            node.commands.wait_on(watched)
        if session.paused:
            executor.spin_once(timeout_sec=SERVE_PERIOD_S)
            node.take_commands()             # still taken and held while paused
            next_serve = 0.0
            continue
        if session.sample_held:              # a controller switch at this tick, unconfirmed
            if not session.release(node.send):
                executor.spin_once(timeout_sec=SERVE_PERIOD_S)
            continue
        if ls.stamp_ns is None:              # tick 0, once running
            session.emit(node.send)
        node.take_commands()
        now = time.monotonic()
        if ls.complete:
            session.tick(node.send)          # the pacer's periods: wall time per tick
        if not ls.complete and not session.paused:
            if ls.overdue(now):
                node.lockstep_overdue(now)
            node.commands.wait(min(max(next_serve - now, 0.0), ls.until_overdue(now)))
        if now >= next_serve:
            node.serve(executor)
            next_serve = now + LOCKSTEP_SERVE_PERIOD_S
