"""A driller scenario played by the rig session itself, on its simulated clock: set-points,
parameter changes and a controller switch at exactly the tick of their time, in real time, at
max speed and in lockstep alike, each recorded as it lands (set-points as the commands a
driver would have sent, changes as parameter events, the switch as a controller event), so
``drill_sim bag resim`` redoes them."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..core import ParameterError
from ..wire import rig_topics
from .scenario import Scenario, due

_SPEED = rig_topics.COMMAND_BY_RULE["top_drive"]
_HOOK = rig_topics.COMMAND_BY_RULE["hook_load"]


def checked_changes(scenario: Scenario, p: dict[str, object],
                    check: Callable[[dict[str, object], dict[str, object]], dict[str, object]]
                    ) -> None:
    """Every change of ``scenario``, in turn from the parameters ``p``, checked with
    ``check(old, changes)`` (ParameterError naming the change and what was wrong)."""
    values = dict(p)
    for at_s, change in scenario.changes:
        try:
            values = check(values, change)
        except ParameterError as exc:
            raise ParameterError(f"scenario '{scenario.name}' change at {at_s:g} s: "
                                 f"{exc}") from None


class ScenarioPlayer:
    """A scenario played on a ``RigSession`` (``session``) from the session's time at its
    start."""

    def __init__(self, session: Any, scenario: Scenario,
                 on_switch: Callable[[str], object] | None = None,
                 check: Callable[[dict[str, object], dict[str, object]], dict[str, object]]
                 | None = None) -> None:
        """Play ``scenario`` from now on, on the session's simulated clock: at each tick, once
        the rig has reached its time t, the scenario's parameter changes due by t are made
        (``change``, recorded), its controller switch due by the next tick's time is asked for
        (``on_switch(law)``, recorded; what it returns, a confirmation with ``done()``, is
        held in ``switch_pending`` and a lockstep loop holds the tick's sample until it is
        done), and its set-points for t go in as commands (recorded as received), held until
        the next tick. ``check``: the session's parameters after a change, checked (raises
        ParameterError naming a bad one): ``check(old, changes)``, the parameters after the
        changes; every change is checked here, before anything runs.
        A reset plays the scenario again from its start."""
        self.session = session
        if check is not None:
            checked_changes(scenario, session.p, check)
        self.scenario, self._on_switch = scenario, on_switch
        self._check = check
        self.restart()

    def restart(self) -> None:
        """From the scenario's start, at the session's time now (at start and on reset)."""
        self._t0 = self.session.sim_time_s
        self._next_change = 0
        self._switched = self._recorded = False
        self._held_setpoints: list[float | None] = [None, None]
        self.at_tick()

    def at_tick(self) -> None:
        """The rig is at a tick's time t, its sample emitted, about to advance: the changes
        and set-points due by t go in now (so they act from t on, as a run-time change or a
        command taken between two ticks does), and a switch due by the next tick's time is
        asked for now (so the new law answers the first sample at or after its time)."""
        sc, session = self.scenario, self.session
        t = session.sim_time_s - self._t0
        while self._next_change < len(sc.changes) and due(sc.changes[self._next_change][0], t):
            changes = sc.changes[self._next_change][1]
            self._next_change += 1
            try:
                session.change(self._check(session.p, changes) if self._check is not None
                            else {**session.p, **changes})
            except ParameterError as exc:
                session.log.error(f"scenario '{sc.name}': change at {t:.3f} s refused: {exc}")
        switch = sc.controller
        if switch is not None and not self._switched and \
                due(switch.on_at_s, t + 1.0 / session.p["rate_hz"]):
            self._ask(switch.law)
        speed, hook = sc.commands_at(t, session.rig.params.submerged_weight_n)
        held = self._held_setpoints
        for k, (topic, six) in enumerate((
                (_SPEED, (0.0, 0.0, 0.0, 0.0, 0.0, speed)),
                (_HOOK, (0.0, 0.0, hook, 0.0, 0.0, 0.0)))):
            if six[5 - 3 * k] == held[k]:
                continue
            held[k] = six[5 - 3 * k]
            refusal = session.commands.send(topic, six, internal=True)
            if refusal is None:
                session.commands.last_s = session.clock()     # the rig is being commanded
            elif refusal != "in flight":
                session.log.warning(f"scenario '{sc.name}': {topic.name} at {t:.3f} s refused: "
                                 f"{refusal}")

    def _ask(self, law: str) -> None:
        """Ask for the controller switch: recorded once, asked again at every tick until the
        controller can be asked (a controller still starting up)."""
        session = self.session
        if not self._recorded:
            self._recorded = True
            if session.recorder is not None:
                session.recorder.record_event("controller", session.sim_time_s, {"law": law})
            first = session.sim_time_s + 1.0 / session.p["rate_hz"]
            session.log.info(f"scenario '{self.scenario.name}': controller {law} switched on "
                             f"for the sample at t = {first:.3f} s")
        if self._on_switch is None:
            self._switched = True
            return
        pending = self._on_switch(law)
        if pending is not None:
            self._switched = True
            session.switch_pending = pending
