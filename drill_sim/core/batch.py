"""Many lumped rigs' states stacked, so one compiled call can advance them all with the
kernel's own ``advance`` over the rows (the vector environment, ``drill_sim.gym.vector_env``):
N rigs cost no Python per rig per tick.

Each rig keeps its ``Simulator``; ``RigBatch.adopt`` moves the simulator's arrays into row i
of the stacks and leaves the simulator looking at that row (numpy views), so every method of
the rig (its sample, metrics, state) still reads and writes the same memory the batch steps.
The rigs must share the arrays' shapes (the same preset and step: the same surface nodes).
"""

from __future__ import annotations

import numpy as np

from . import kernel as kn
from .simulator import Simulator

NO_ROWS = np.zeros((0, kn.NO))       # the kernel's output rows when none are wanted


class RigBatch:
    """The stacked state of ``n`` lumped rigs of one shape (``surface_nodes`` nodes)."""

    def __init__(self, n: int, surface_nodes: int) -> None:
        self.x = np.zeros((n, kn.NX))
        self.k = np.zeros((n, kn.NK), dtype=np.int64)
        self.surf = np.zeros((n, surface_nodes))
        self.p = np.zeros((n, kn.NP))
        self.c = np.zeros((n, kn.NC))
        self.acc = np.zeros((n, kn.NA))

    def adopt(self, i: int, sim: Simulator) -> None:
        """Row i becomes ``sim``'s state: copied in, and ``sim`` reads and writes it there."""
        if sim._surf.shape != self.surf.shape[1:]:
            raise ValueError(f"a rig of {sim._surf.size} surface nodes in a batch of "
                             f"{self.surf.shape[1]}")
        for name in ("x", "k", "surf", "p", "c", "acc"):
            row = getattr(self, name)[i]
            row[:] = getattr(sim, "_" + name)
            setattr(sim, "_" + name, row)
