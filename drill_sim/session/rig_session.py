"""``RigSession``: one rig session without ROS, the object the node, ``drill_sim bag resim`` and
the tests all run.

It owns the ``Rig``, its ``SensorBank``, the encoders of the rig's messages, the recorder, the
time offset of resets, pause/step/reset, the commands and their rules (the in-flight rule of a
drive-mode change included), run-time parameter changes (all or nothing), the pacing and the
lockstep rule, and the events a bag records. Its verbs are the session's: ``commands``
(``SessionCommands``: ``command``, ``send``, ``receive``), ``advance`` and ``emit`` (a tick:
advance, then the tick's outputs as bytes), ``reset``, ``change``, ``status``. A ROS node
only binds it to topics and services (``drill_sim.ros.node``).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from ..core import NoSteadyDrilling, ParameterError
from ..core.figures import figures_line, string_first_mode
from ..core.parameters import RigParameters
from ..core.rig_sample import RigSample
from ..core.sensor_profile import SensorProfile
from ..core.sensors import Measured, session_sensors
from ..core.string_geometry import StringGeometry
from ..wire import rig_topics
from . import rules
from .diagnostics import CommandCounts, Status, rig_status
from .lockstep import Lockstep
from .pacing import Pacer
from .parameter_table import SPLITS
from .recorder import SessionRecorder
from .rig_messages import TickOutputs
from .scenario import Scenario
from .scenario_player import ScenarioPlayer
from .session_commands import SessionCommands

Send = Callable[[bytes], object]


@dataclass(frozen=True)
class Naming:
    """How the session's topics are named where it runs: ``node``, the rig node's fully
    qualified name; ``resolve``, a table name (``~/joint_states``) to the full topic name
    (remappings applied). Offline, the default rig's own names."""

    node: str = "/" + rig_topics.NODE_NAME
    resolve: Callable[[str], str] | None = None

    def topic(self, name: str) -> str:
        if self.resolve is not None:
            return self.resolve(name)
        return self.node + name[1:] if name.startswith("~") else name


class RigSession:
    """A rig session built from its parameters ``p`` (the parameter table's names, checked:
    ``drill_sim.session.parameter_table``).

    geometry: the pipe of the distributed string (the preset's, or a bag's); step_s: the
    integration step [s] (default: the largest divisor of the tick not above ``dt_s``; a bag
    gives its own); sensor_profile: the profile (default: the one ``p`` names); preset: its
    name, for the bag; naming: the topics' full names (for the bag); log: where the session
    says what it did (a ``logging.Logger`` or an rclpy logger); clock: the wall clock [s]
    (monotonic) of pacing, lockstep and command ages; rig: the rig's SI parameters as the
    caller holds them (a preset's: the rig is built from them, ``p``'s entries show them;
    None: built from ``p``'s, as a ROS table or a bag gives them). Raises ParameterError or
    NoSteadyDrilling if ``p`` makes no rig, RecordRefused if ``p["record"]`` cannot be opened.
    """

    def __init__(self, p: dict[str, object], *, geometry: StringGeometry | None = None,
                 step_s: float | None = None, sensor_profile: SensorProfile | None = None,
                 preset: str = "", naming: Naming | None = None, log=None,
                 clock: Callable[[], float] = time.monotonic, record: bool = True,
                 rig: RigParameters | None = None) -> None:
        self.p = dict(p) if rig is None else {**p, **rig.as_dict()}
        self.log = log if log is not None else logging.getLogger("drill_sim.session")
        self.clock = clock
        self.naming = naming or Naming()
        self.rig = rules.make_rig(self.p, step_s, geometry=geometry, params=rig)
        rules.start(self.rig, self.p)
        self._layer = self.rig.layer            # the formation at the start
        self.sensors = session_sensors(self.p, self.rig.dt_s, sensor_profile)
        self.sensors.warm_up()
        self.with_clock = bool(self.p.get("publish_clock", False))
        self.tick_outputs = TickOutputs(self.with_clock,
                                        self.p.get("measured_publish") == "on_sample")
        self.outputs = self.tick_outputs.topics        # in publishing order
        self.offset_s = 0.0                      # simulated time before the last reset
        self.paused = bool(self.p.get("start_paused", False))
        self.last: tuple[int, RigSample, Measured] | None = None   # stamp, sample, reading
        self.lockstep = Lockstep(tuple("~/" + n for n in self.p["lockstep_topics"]),
                                 self.p["lockstep_timeout_s"]) if self.p.get("lockstep") else None
        self.epoch_ns = 0 if self.with_clock else time.time_ns()   # stamps' origin [ns]
        self.pacer = Pacer(self.p.get("rate_hz", 1000.0), self.p.get("real_time_factor", 1.0),
                           self.back_to_back(self.p), self.p.get("diagnostics_period_s", 1.0),
                           self.rig.time_s, clock=clock)
        self._steps_per_tick = self._tick_steps(self.p.get("rate_hz", 1000.0))
        self.commands = SessionCommands(self)    # command, send, receive: the node's rules
        self.player: ScenarioPlayer | None = None
        self.switch_pending = None              # a controller switch not yet confirmed
        self.sample_held = False                # a tick's sample held until it is
        self.recorder = SessionRecorder(
            p=self.p, rig=self.rig, preset=preset, node=self.naming.node,
            resolve=self.naming.topic, stamp_epoch_ns=self.epoch_ns, logger=self.log,
            sensors=self.sensors.profile) if record and self.p.get("record") else None

    # ---- settings ------------------------------------------------------------------
    @staticmethod
    def back_to_back(p: dict) -> bool:
        """Ticks back to back, one tick each (max speed, lockstep), not paced by the clock."""
        return bool(p.get("max_speed")) or bool(p.get("lockstep"))

    def _tick_steps(self, rate_hz: float) -> int:
        """Steps of the session's step in one tick of 1/``rate_hz`` (a whole number)."""
        return round(1.0 / (rate_hz * self.rig.dt_s))

    @property
    def steps_per_tick(self) -> int:
        return self._steps_per_tick

    def figures(self) -> str:
        """The rig's key figures in one line (the torsional frequency is the lumped model's;
        on the distributed string its own first mode is added)."""
        line = figures_line(self.rig.params)
        if self.rig.string_model == "distributed" and self.rig.geometry is not None:
            line += f"; the distributed string's {string_first_mode(self.rig)}"
        return line

    # ---- time ----------------------------------------------------------------------
    @property
    def sim_time_s(self) -> float:
        """Simulated time since the session started [s]; it keeps running across resets."""
        return self.offset_s + self.rig.time_s

    def stamp_ns(self) -> int:
        """The stamp of the current sample [ns]: simulated time with /clock, else the wall
        clock at start plus simulated time."""
        return self.epoch_ns + round(self.sim_time_s * 1e9)

    # ---- the tick ------------------------------------------------------------------
    def advance(self, ticks: int) -> bool:
        """Advance the rig by exactly ``ticks`` ticks of 1/``rate_hz``; False (and paused) if
        the model refuses a step."""
        try:
            if self.player is None:
                self.rig.advance_steps(ticks * self._steps_per_tick)
            else:                       # the scenario's events at every tick they fall on
                for _ in range(ticks):
                    self.player.at_tick()
                    self.rig.advance_steps(self._steps_per_tick)
        except ParameterError as exc:   # a step the model refuses: hold the state, say why
            self.paused = True
            self.log.error(f"simulation paused: {exc}; change the commands or parameters, "
                           "then resume with ~/pause false or ~/reset")
            return False
        if self.rig.layer != self._layer:
            self._entered_formation()
        return True

    def _entered_formation(self) -> None:
        """The bit entered another formation: said, and recorded as an event."""
        self._layer = layer = self.rig.layer
        rock = {k: f"{v:.6g}" for k, v in self.rig.rock.items()}
        where = f"formation {layer} (top {self.rig.formations[layer].top_m:g} m)" \
            if layer >= 0 else "the rock above the first formation"
        self.log.info(f"the bit entered {where} at {self.rig.bit_measured_depth_m:.3f} m MD, "
                      f"t = {self.sim_time_s:.3f} s: " + ", ".join(f"{k} {v}"
                                                               for k, v in rock.items()))
        if self.recorder is not None:
            self.recorder.record_event("formation", self.sim_time_s,
                                       {"layer": str(layer), **rock})

    def set_live(self, live: Sequence[bool]) -> None:
        """Which outputs are published (and, not recording, encoded)."""
        self.tick_outputs.set_live(live)

    def emit(self, send: Sequence[Send]) -> int:
        """The current sample measured and encoded once, each live output's bytes handed to
        ``send[k]`` (its publisher) and the very same bytes recorded (``TickOutputs.emit``);
        in lockstep, the tick's answers awaited from here. Its stamp [ns]."""
        stamp = self.stamp_ns()
        s = self.rig.sample()
        m = self.tick_outputs.emit(stamp, s, self.sensors, self.rig.time_s, self.recorder, send)
        self.last = (stamp, s, m)
        if self.lockstep is not None:
            self.lockstep.wait_for(stamp, self.clock())
        return stamp

    def emit_again(self, send: Sequence[Send]) -> None:
        """The last sample's outputs sent again to every output (not recorded again): a
        lockstep tick overdue, for a controller that started or restarted late."""
        if self.last is not None:
            self.tick_outputs.again(self.last, send)

    def tick(self, send: Sequence[Send] | None = None) -> bool:
        """One tick, as lockstep and max speed run it: advance one tick and emit its sample
        (to ``send``, or to nowhere); False if paused or the model refused the step."""
        if self.paused:
            return False
        self.pacer.tick_started()
        if not self.advance(1):
            return False
        self.pacer.advanced(1)
        if self.holding:                 # a controller switch at this tick: held until done
            self.sample_held = True
            return True
        self.emit(send if send is not None else _NOWHERE * len(self.outputs))
        return True

    def release(self, send: Sequence[Send]) -> bool:
        """The sample a controller switch held back, emitted once the switch is confirmed;
        True if it was."""
        if self.sample_held and not self.holding:
            self.sample_held = False
            self.emit(send)
            return True
        return False

    def advance_and_emit(self, ticks: int, send: Sequence[Send]) -> bool:
        """Advance ``ticks`` ticks and emit the sample: one sample for all of them, or, while a
        scenario plays, one each (its set-points go in at every tick, so every tick's sample
        is kept for a re-run to apply them at). False if the model refused a step."""
        if self.player is None or ticks == 1:
            if not self.advance(ticks):
                return False
            self.emit(send)
            return True
        for _ in range(ticks):
            if not self.advance(1):
                return False
            self.emit(send)
        return True

    # ---- a scenario on the simulated clock ---------------------------------------------
    def play(self, scenario: Scenario, on_switch: Callable[[str], object] | None = None,
             check: Callable[[dict[str, object], dict[str, object]], dict[str, object]]
             | None = None) -> None:
        """Play ``scenario`` from now on, on the session's simulated clock
        (``ScenarioPlayer``): every set-point, change and switch at exactly the tick of its
        time. ``on_switch(law)`` asks the controller; ``check(old, changes)``, the parameters
        after a change, checked (ParameterError naming a bad one), for every change now."""
        self.player = ScenarioPlayer(self, scenario, on_switch, check)

    @property
    def scenario(self) -> Scenario | None:
        return None if self.player is None else self.player.scenario

    @property
    def holding(self) -> bool:
        """A controller switch is asked for and not yet confirmed."""
        pending = self.switch_pending
        if pending is None:
            return False
        if pending.done():
            self.switch_pending = None
            return False
        return True

    # ---- pause, step, reset ----------------------------------------------------------
    def pause(self, paused: bool) -> str:
        if self.paused and not paused:
            self.pacer.anchor()
        self.paused = bool(paused)
        return "paused" if self.paused else "running"

    def step(self, send: Sequence[Send]) -> tuple[bool, str]:
        """One tick while paused: (done, message)."""
        if not self.paused:
            return False, "step works only while paused"
        if not self.advance(1):
            return False, "the model refused the step"
        self.emit(send)
        return True, f"stepped to t = {self.sim_time_s:.6f} s"

    def reset(self, send: Sequence[Send] | None) -> tuple[bool, str]:
        """Back to the initial state; simulated time goes on; the initial state's sample
        emitted to ``send`` (None: not emitted, as a re-run that meets the recorded sample
        next). (done, message)."""
        offset = self.offset_s + self.rig.time_s
        try:
            rules.start(self.rig, self.p)
        except (ParameterError, NoSteadyDrilling) as exc:
            return False, str(exc)
        if self.recorder is not None:
            self.recorder.record_event("reset", self.sim_time_s)
        self.offset_s = offset
        self._layer = self.rig.layer
        self.sensors.reset()
        self.pacer.reset(self.rig.time_s)
        if self.player is not None:
            self.player.restart()
        if send is not None:
            self.emit(send)
        return True, f"reset to the initial state ({self.p['initial_state']})"

    # ---- parameters at run time ------------------------------------------------------
    def change(self, new: dict[str, object]) -> set[str]:
        """Every parameter to the values ``new``, all or nothing; the names that changed.
        Raises ParameterError, the session as it was, if the rig refuses them."""
        changed = rules.apply_changes(self.rig, self.p, new)
        if new.get("top_drive_mode") != self.p.get("top_drive_mode"):
            self.commands.mode_left(self.p.get("top_drive_mode"))
            if self.lockstep is not None:
                mode = str(new.get("top_drive_mode"))
                if (moved := self.lockstep.follow_drive_mode(mode)) is not None:
                    self.log.info(f"lockstep: the drive is in {mode} mode now; each tick "
                                  f"waits for its command on {moved} (lockstep_topics says "
                                  "where the session started)")
        self.p = dict(new)
        if changed & set(rules.RIG_FIELDS):
            self.log.info(f"rig figures now: {self.figures()}")
        if changed and self.recorder is not None:
            self.recorder.record_event("parameters", self.sim_time_s,
                                       {k: str(new[k]) for k in sorted(changed)})
        if "rate_hz" in new:
            self.pacer.configure(new["rate_hz"], new["real_time_factor"], self.back_to_back(new))
            self._steps_per_tick = self._tick_steps(new["rate_hz"])
        self.tick_outputs.on_sample = new.get("measured_publish") == "on_sample"
        if self.lockstep is not None:
            self.lockstep.timeout_s = new["lockstep_timeout_s"]
        if changed & set(SPLITS) and self.recorder is not None:
            self.recorder.set_split(new["record_split_duration_s"],
                                    new["record_split_size_bytes"])
        return changed

    # ---- status --------------------------------------------------------------------
    def status(self, *, commands: CommandCounts, other_publishers: tuple[str, ...] = ()
               ) -> Status:
        """The session's status for /diagnostics over the window since the last call."""
        now = self.clock()
        ticks = self.pacer.window(self.rig.time_s)
        metrics = self.rig.metrics()
        self.rig.reset_metrics_window()
        p = self.p
        expected_hz = p["rate_hz"] * (1.0 if self.pacer.max_speed
                                      else min(1.0, p["real_time_factor"]))
        return rig_status(
            self.rig.sample(), metrics, ticks, paused=self.paused,
            record_error=self.recorder.error if self.recorder is not None else None,
            command_age_s=now - self.commands.last_s, command_timeout_s=p["command_timeout_s"],
            rate_hz=expected_hz, max_speed=self.pacer.max_speed,
            lockstep=None if self.lockstep is None else self.lockstep.status(now),
            sim_time_s=self.sim_time_s, real_time_factor=p["real_time_factor"],
            other_publishers=other_publishers, commands=commands,
            every_tick_sampled=self.player is not None)

    def close(self) -> None:
        """Close the bag (if recording)."""
        if self.recorder is not None:
            self.recorder.close()


_NOWHERE: list[Send] = [lambda raw: None]

