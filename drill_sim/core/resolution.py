"""What step a run may take: the fastest mode's period and the largest step that resolves it
(the one test every refusal of a step uses), and the rock surface's grid tied to the step."""

from __future__ import annotations

import math

from .parameters import Groups
from .top_drive import DriveGroups

MAX_NODES = 2**22            # surface memory cap: 32 MiB


STEPS_PER_PERIOD = 20       # the fastest mode's period holds at least this many steps


def fastest_period(groups: Groups, drive: DriveGroups | None = None) -> float:
    """Period [t*] of the fastest mode: axial in contact, 2 pi/sqrt(n psi) (the cutting law's
    stiffness n against the axial inertia), or torsional, 2 pi (with a top drive in the loop,
    2 pi/sqrt(1 + 1/j) or the speed PI's, ``DriveGroups.fastest_frequency``), whichever is
    shorter."""
    torsional = 1.0 if drive is None else drive.fastest_frequency()
    return 2.0 * math.pi / math.sqrt(max(groups.n * groups.psi, torsional**2))


def max_step(groups: Groups, drive: DriveGroups | None = None) -> float:
    """The largest step [t*] that resolves the fastest mode: its period / STEPS_PER_PERIOD.

    The midpoint scheme's phase error on an oscillation of frequency f is (h f)^2/24 per
    radian; at 20 steps a period (h f = 0.31) that is 0.4 % of the frequency, and the stick and
    contact events of the bit, which last a fraction of the axial period, are still seen by a
    few steps. A step of a period or more lets the stick law hold the bit for good (psi = 1e4,
    dt = 0.05: stick fraction 1.0 where a resolving step gives none)."""
    return min(0.05, fastest_period(groups, drive) / STEPS_PER_PERIOD)


def resolves(groups: Groups, drive: DriveGroups | None, dt: float) -> bool:
    """Whether step ``dt`` [t*] resolves the fastest mode (``max_step``, to round-off): the one
    test every refusal of a step uses (the simulators, ``Rig``, the command line)."""
    return dt <= max_step(groups, drive) * (1.0 + 1e-12)


def surface_nodes(groups: Groups, dt: float) -> int:
    """Nodes per sector: the power of two that makes a node about one step of rotation at omega ~ 1.

    Tying the angular grid to the step keeps the scheme's error one function of dt.
    """
    wanted = (2.0 * math.pi / groups.n) / dt
    return int(min(MAX_NODES, max(64, 2 ** math.ceil(math.log2(wanted)))))
