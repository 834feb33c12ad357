"""The offline closed loop: a ``RigSession`` (the object the rig node runs) ticked at the
controller's sample period h, a law under the ``Supervisor`` on the session's sensor readings,
and the metrics that score it (msg_docs/control.md, "Evaluation").

The session runs at ``rate_hz = 1/h`` with the node's rules: its step is the largest divisor of
h not above the default step (100 µs at 1 kHz on base), so the samples fall exactly on k·h as
the node's ticks do; its sensors measure each tick's sample (ideal by default); the law's
output goes in as the node's commands do (``~/cmd/top_drive_torque``, or ``~/cmd/top_drive``
for the kinematic drive) and is held until the next sample (zero-order hold). So the same law
at the same h gives the same numbers here and through the nodes in lockstep, and a loop
recorded here (``record``) is a bag ``drill_sim bag resim`` re-runs exactly.

Torque laws drive a top drive in ``torque`` mode (inertia, limits, rate and lag as given);
``kinematic`` drives the seed's ideal speed source. The session starts on the steady state at
the scenario's first set-point, perturbed by ``LoopSettings.perturbation`` (the session's
``initial_perturbation``) so stick-slip grows where it can; the law (before a switch-on, the
drive's own stiff speed loop) takes over bumplessly from the torque the drive holds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from ..core import RPM, Preset, RigSample, load_preset
from ..core.parameters import ParameterError, check_number
from ..core.sensors import Measured
from ..session import rules
from ..session.parameter_table import checked_change, specs
from ..session.rig_session import RigSession
from ..session.scenario import due
from ..session.scenario_player import checked_changes
from ..wire import rig_topics
from . import LAWS
from .evaluation import (
    LoopResult,
    LoopSettings,
    Scenario,
    law_gains,
    law_top_drive,
    loop_result,
)
from .laws import SurfaceMeasurement
from .supervisor import Supervisor
from .tuning import pipe_impedance

SPEED = rig_topics.COMMAND_BY_RULE["top_drive"]
HOOK = rig_topics.COMMAND_BY_RULE["hook_load"]
TORQUE = rig_topics.COMMAND_BY_RULE["top_drive_torque"]
SERIES = ("time_s", "bit_speed_rad_s", "top_drive_speed_rad_s", "surface_torque_nm",
          "motor_torque_nm", "law_output", "stuck", "bit_depth_m", "top_drive_angle_rad",
          "wob_n")


def session_parameters(preset: Preset, scenario: Scenario, settings: LoopSettings,
                       record: Path | None = None) -> dict[str, object]:
    """The rig session's parameters for this loop: the node's table at the preset's
    defaults, ticking at 1/h with /clock, the law's drive, the settings' string and sensors,
    a steady start at the scenario's first set-point."""
    h = check_number("sample_period_s", settings.sample_period_s, high=1.0)
    drive = law_top_drive(preset, settings.law, settings.top_drive)
    speed_set, wob_kn = scenario.values(np.zeros(1))
    start = speed_set[0] if scenario.start_rpm is None else scenario.start_rpm * RPM  # checked
    p = {s.name: s.default for s in specs(preset)}
    p.update(publish_clock=True, max_speed=True, rate_hz=1.0 / h,
             string_model=settings.string_model, sensor_profile=settings.sensor_profile,
             sensor_seed=settings.sensor_seed, initial_state=scenario.initial_state,
             initial_top_drive_speed_rad_s=float(start),
             initial_weight_on_bit_n=float(1e3 * wob_kn[0]),
             initial_perturbation=settings.perturbation, record=str(record or ""),
             max_top_drive_speed_rad_s=max(p["max_top_drive_speed_rad_s"], 40.0))
    for name in rules.TOP_DRIVE_FIELDS:
        value = getattr(drive, name)
        p[name] = 0.0 if name == "motor_torque_rate_nm_s" and math.isinf(value) else value
    return p


def tick_commands(preset: Preset, scenario: Scenario, h: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(speed set-point [rad/s], hook load [N]) at each tick k h of the scenario, k = 0..n:
    the very numbers the offline loop and the nodes' lockstep run use."""
    n = math.floor(scenario.duration_s / h + 1e-9)
    speed_set, wob_kn = scenario.values(np.arange(n + 1) * h)
    hook = preset.rig.submerged_weight_n - 1e3 * wob_kn
    if np.any(hook < 0.0):
        raise ParameterError(f"wob_kn up to {wob_kn.max():g} kN is out of range: expected at "
                             f"most W_s = {preset.rig.submerged_weight_n / 1e3:g} kN")
    return speed_set, hook


class LoopStepper:
    """The offline loop one sample at a time, its law outside: ``start`` gives sample 0 and
    its reading, each ``step(output)`` holds that command over the next period h and gives the
    next sample; ``finish`` records the last output, ``result`` scores the run. ``run_loop``
    puts a law under the ``Supervisor`` here; the Gymnasium environment (``drill_sim.gym``)
    puts a policy. ``output`` is a motor torque [N·m] (a torque law's drive) or the speed
    command [rad/s] (the kinematic drive's)."""

    def __init__(self, preset: Preset | str, scenario: Scenario, settings: LoopSettings, *,
                 record: str | Path | None = None) -> None:
        preset = load_preset(preset) if isinstance(preset, str) else preset
        self.preset, self.scenario, self.settings = preset, scenario, settings
        p = session_parameters(preset, scenario, settings, Path(record) if record else None)
        self.h = h = float(settings.sample_period_s)       # checked by session_parameters
        self.drive = law_top_drive(preset, settings.law, settings.top_drive)
        self.speed_set, self.hook = tick_commands(preset, scenario, h)
        self.n = self.speed_set.size - 1
        self.check = partial(checked_change, {s.name: s for s in specs(preset)})
        checked_changes(scenario, p, self.check)          # every change, before anything runs
        self.session = RigSession(p, geometry=preset.string, preset=preset.name, rig=preset.rig)
        self.session.set_live([False] * len(self.session.outputs))   # nobody subscribes
        self.commands = _Commands(self.session)
        self.window_k = max(1, math.ceil(scenario.metrics_from_s / h - 1e-9))
        self.switch_k = scenario.switch_on_sample(h)
        self.speed_law = LAWS[settings.law].output_kind == "speed"
        self.measure = _measure(settings)              # what a law reads of a tick
        self.series = {k: np.empty(self.n + 1) for k in SERIES}
        self.k = 0
        self._changes = list(scenario.changes)

    @property
    def rig(self):
        return self.session.rig

    def start(self) -> tuple[RigSample, Measured]:
        """Sample 0 (the steady start) and what the sensors read of it."""
        self.session.emit(())
        return self.session.last[1], self.session.last[2]

    def step(self, output: float) -> tuple[RigSample, Measured]:
        """``output`` for the current sample k, held over k..k+1; sample k + 1 and its
        reading (the scenario's changes due made first, as the node's player does)."""
        k, session = self.k, self.session
        _record(self.series, k, session.last[1], output)
        while self._changes and due(self._changes[0][0], k * self.h):
            session.change(self.check(session.p, self._changes.pop(0)[1]))
        if self.speed_law:
            self.commands.send(float(output), float(self.hook[k]))
        else:
            self.commands.send(float(self.speed_set[k]), float(self.hook[k]), float(output))
        if k + 1 == self.switch_k and session.recorder is not None:
            # as the node's scenario player records it: the tick before the law's first sample
            session.recorder.record_event("controller", session.sim_time_s,
                                          {"law": self.settings.law})
        session.tick()
        self.k = k = k + 1
        if k == self.window_k:
            self.rig.reset_metrics_window()
        return session.last[1], session.last[2]

    def supervisor(self, law: str, gains: Mapping[str, float] | None = None) -> Supervisor:
        """``law`` under the ``Supervisor``, taking over bumplessly from the torque the drive
        holds now, set to the current sample's set-point; ``gains`` None: the drive's own
        stiff loop's (its torque limits the drive's)."""
        if gains is None:
            gains = law_gains(LoopSettings(law=law), self.drive)
        sup = Supervisor(self.h, pipe_impedance(self.preset),
                         self.drive.top_drive_inertia_kg_m2, law, gains,
                         speed_set_rad_s=float(self.speed_set[self.k]))
        sup.last_output = self.rig.commanded_motor_torque_nm
        return sup

    def finish(self, output: float) -> None:
        """Record the last sample's output (the law's answer to it)."""
        _record(self.series, self.k, self.session.last[1], output)

    def result(self) -> LoopResult:
        return loop_result(self.preset, self.scenario, self.settings, self.drive, self.rig,
                           self.series, self.window_k)

    def close(self) -> None:
        self.session.close()


def run_loop(preset: Preset | str, scenario: Scenario, settings: LoopSettings, *,
             progress: Callable[[float], None] | None = None,
             record: str | Path | None = None) -> LoopResult:
    """Close the loop over the scenario (module docstring); ``record``: a new bag directory
    the session is recorded into, as the node records it."""
    loop = LoopStepper(preset, scenario, settings, record=record)
    try:
        _close(loop, progress)
    finally:
        loop.close()
    return loop.result()


def _close(loop: LoopStepper, progress: Callable[[float], None] | None) -> None:
    settings, speed_set, n, switch_k = loop.settings, loop.speed_set, loop.n, loop.switch_k
    measure = loop.measure
    gains = law_gains(settings, loop.drive)
    # the kinematic pass-through: its output is the set-point, Ω_set itself, every tick
    sample, reading = loop.start()                    # the sample at t = 0, measured
    if loop.speed_law:
        output = loop.rig.commanded_speed_rad_s        # bumpless: the speed the drive holds
    else:                                             # before a switch, the drive's stiff loop
        sup = loop.supervisor(settings.law, gains) if switch_k == 0 else \
            loop.supervisor("stiff_pi")
        output = sup.step(measure(sample, reading))
    every = max(1, n // 200)
    for k in range(1, n + 1):
        sample, reading = loop.step(output)
        if loop.speed_law:
            output = float(speed_set[k])
        else:
            if k == switch_k:
                sup.replace_law(settings.law, gains)      # bumpless: from the last output
            sup.set_speed(float(speed_set[k]))
            output = sup.step(measure(sample, reading))
        if progress is not None and k % every == 0:
            progress(k / n)
    loop.finish(output)


def _measure(settings: LoopSettings) -> Callable[[RigSample, Measured], SurfaceMeasurement]:
    """What the law reads of a tick: a custom sensor's view of the sample, or the session's
    sensors' reading (under ``ideal``, the sample's own values)."""
    if settings.measure is not None:
        custom = settings.measure
        return lambda sample, reading: custom(sample)
    return lambda sample, m: SurfaceMeasurement(sample.time_s, m.top_drive_speed_rad_s,
                                                m.motor_torque_nm, m.surface_torque_nm)


class _Commands:
    """The loop's commands into the session as the node takes them, each sent when its value
    changes (the session holds it meanwhile; ``SessionCommands.send`` records it as the
    message a driver would have sent)."""

    def __init__(self, session: RigSession) -> None:
        self.session = session
        self.held: list[float | None] = [None, None, None]      # speed, hook, torque

    def send(self, speed: float, hook: float, torque: float | None = None) -> None:
        held = self.held
        if speed != held[0]:
            held[0] = speed
            self._one(SPEED, (0.0, 0.0, 0.0, 0.0, 0.0, speed))
        if hook != held[1]:
            held[1] = hook
            self._one(HOOK, (0.0, 0.0, hook, 0.0, 0.0, 0.0))
        if torque is not None and torque != held[2]:
            held[2] = torque
            self._one(TORQUE, (0.0, 0.0, 0.0, 0.0, 0.0, torque))

    def _one(self, topic: rig_topics.RigTopic, six: tuple[float, ...]) -> None:
        refusal = self.session.commands.send(topic, six)
        if refusal is not None:
            raise ParameterError(f"the loop's {topic.name} command was refused: {refusal}")


def _record(series: dict[str, np.ndarray], k: int, s: RigSample, output: float) -> None:
    series["time_s"][k] = s.time_s
    series["bit_speed_rad_s"][k] = s.bit_speed_rad_s
    series["top_drive_speed_rad_s"][k] = s.top_drive_speed_rad_s
    series["surface_torque_nm"][k] = s.surface_torque_nm
    series["motor_torque_nm"][k] = s.motor_torque_nm
    series["law_output"][k] = output
    series["stuck"][k] = s.stuck
    series["bit_depth_m"][k] = s.bit_depth_m
    series["top_drive_angle_rad"][k] = s.top_drive_angle_rad
    series["wob_n"][k] = s.wob_n


def run_laws(preset: Preset | str, scenario: Scenario, laws: Sequence[str],
             base: LoopSettings | None = None, *,
             gains: Mapping[str, Mapping[str, float]] | None = None) -> list[LoopResult]:
    """Each law in turn on the same scenario and settings (gains per law name)."""
    base = base or LoopSettings(law="kinematic")
    gains = gains or {}
    return [run_loop(preset, scenario, replace(base, law=name, gains=gains.get(name, {})))
            for name in laws]
