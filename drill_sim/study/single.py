"""One simulation: the path ``drill_sim simulate`` and every point of ``drill_sim map`` share.

``RunSettings`` describes a run completely in dimensionless units (a few numbers, cheap to send
to another process or machine); ``run_single`` runs it and returns the sampled trajectories, if
asked for, and the metrics over the run's last part (the metrics window); ``point_metrics`` is
the function a map sends to its workers. A new model option (a string model, a top-drive
controller) is one more field of ``RunSettings`` used in ``run_single``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..core import Groups, Metrics, Simulator, Trajectory
from ..core.distributed import StringWaves
from ..core.distributed_simulator import StringSimulator
from ..core.top_drive import DriveGroups

STARTS = ("steady", "rest")


@dataclass(frozen=True)
class RunSettings:
    """Everything one run needs, dimensionless (the model contract's scaling).

    The run lasts ``lead + window`` [t*]; the metrics are taken over the last ``window``.
    """

    groups: Groups
    w0: float                  # available weight W0/F*
    omega0: float              # top-drive speed Omega0 t*
    dt: float                  # fixed step [t*]
    lead: float                # time run before the metrics window [t*]
    window: float              # the metrics window [t*]
    start: str = "steady"      # "steady": exact steady drilling; "rest": bit at rest
    gap: float = 0.0           # with start "rest": bit height above bottom [L*]
    perturbation: float = 1e-3  # relative perturbation of the initial bit speed (steady start)
    drive: DriveGroups | None = None   # the top drive; None: kinematic (the seed's)
    motor_torque: float | None = None  # torque mode's command [C]; None: the start's (steady
                                       # torque, or 0 at rest)
    waves: StringWaves | None = None  # the distributed string at step dt; None: lumped string

    @property
    def string_model(self) -> str:
        return "lumped" if self.waves is None else "distributed"

    @property
    def steps(self) -> int:
        """Steps the run takes (as ``Simulator.run`` rounds each part)."""
        lead = round(self.lead / self.dt) if self.lead > 0 else 0
        return lead + round(self.window / self.dt)


@dataclass(frozen=True)
class SingleRun:
    """A run's sampled parts (before the window, if any, then the window) and window metrics."""

    parts: tuple[Trajectory, ...]
    metrics: Metrics


def default_start(groups: Groups, w0: float, omega0: float) -> str:
    """``steady`` when steady drilling exists (w0 > lambda and omega0 > 0), else ``rest``."""
    return "steady" if w0 > groups.lam and omega0 > 0 else "rest"


def run_single(settings: RunSettings, *, output_interval: float | None = None,
               progress: Callable[[float], None] | None = None) -> SingleRun:
    """Run ``settings``; keep samples every ``output_interval`` [t*] (None: none);
    ``progress(fraction)`` is called between chunks."""
    s = settings
    sim = (Simulator(s.groups, s.dt, drive=s.drive) if s.waves is None
           else StringSimulator(s.groups, s.waves, drive=s.drive))
    if s.start == "steady":
        sim.start_steady(s.w0, s.omega0, s.perturbation)
    else:
        sim.start_at_rest(s.gap)
        sim.set_commands(s.w0, s.omega0)
    if s.motor_torque is not None:
        sim.set_motor_torque(s.motor_torque)
    total = s.lead + s.window
    parts = []
    if s.lead > 0:
        report = None if progress is None else (lambda f: progress(f * s.lead / total))
        parts.append(sim.run(s.lead, output_interval=output_interval, progress=report))
    sim.reset_window()
    report = None if progress is None else (lambda f: progress((s.lead + f * s.window) / total))
    parts.append(sim.run(s.window, output_interval=output_interval, progress=report))
    return SingleRun(tuple(parts), parts[-1].metrics)


def point_metrics(settings: RunSettings) -> Metrics:
    """The window metrics of one run, nothing sampled: one point of a map."""
    return run_single(settings).metrics
