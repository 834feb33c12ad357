"""Many rigs' states stacked, so one compiled call can advance them all with the kernels' own
``advance`` over the rows (the vector environment, ``drill_sim.gym.vector_env``): N rigs cost
no Python per rig per tick.

Each rig keeps its simulator and its sensor bank; ``adopt`` moves their arrays into row i of
the stacks and leaves them looking at that row (numpy views), so every method of the rig (its
sample, metrics, state, noise refills) still reads and writes the memory the batch steps. The
rigs share one shape: one preset, step, string model and sensor profile. What a distributed
string does not change while it runs (its lines' impedances, delays, dashpots, low-pass gains
and the wall's friction) is the same for every rig and kept once, from the first.
"""

from __future__ import annotations

import numpy as np

from . import state_layout as sl
from .distributed_simulator import LineArrays
from .sensors import SensorBank
from .simulator import Simulator

_BANK = ("_par", "_state", "_istate", "_ring", "_noise", "_window", "_x", "_out", "_fresh")
# what running a distributed string does not change: the same for every rig, kept once
_SHARED = tuple(f"{line}.{name}" for line in ("torsion", "axial")
                for name in (*LineArrays.FIXED, "lowpass"))


def _stacked(n: int, a: np.ndarray) -> np.ndarray:
    return np.zeros((n, *a.shape), dtype=a.dtype)


class RigBatch:
    """The stacked state of ``n`` rigs shaped as ``sim`` and ``bank`` (the first rig's): each
    array the simulator steps (``Simulator.arrays``) stacked where it is a rig's own, kept once
    where it is shared; ``string_args``: a distributed string's lines, wall and work arrays as
    ``distributed_kernel.advance`` takes them, stacked where a rig's own (a lumped string:
    arrays of their types, never read)."""

    def __init__(self, n: int, sim: Simulator, bank: SensorBank) -> None:
        self.distributed = sim.MODEL == sl.DISTRIBUTED
        self.no_rows = np.zeros((0, sl.OUTPUTS.size(sim.MODEL)))
        arrays = sim.arrays()
        self.own = {name: _stacked(n, a) for name, a in arrays.items() if name not in _SHARED}
        self.shared = {name: arrays[name] for name in _SHARED if name in arrays}
        self.x, self.k, self.surf, self.p, self.c, self.acc = (
            self.own[name] for name in ("x", "k", "surface", "p", "c", "acc"))
        self.bank = {name: _stacked(n, getattr(bank, name)) for name in _BANK}
        self.window_s = bank._window_s
        if self.distributed:
            self.string_args = (self._line("torsion"), self._line("axial"), sim._wall,
                                (self.own["scratch"], self.own["slots"], self.own["stuck"]))
        else:                                # the distributed arguments' types, never read
            f1, i1 = np.zeros(1), np.zeros(1, dtype=np.int64)
            f2, f3 = np.zeros((1, 1)), np.zeros((1, 1, 1))
            line = (f1, i1, f1, f1, f1, i1, f2, f2, f3)
            self.string_args = (line, line, (f1, f1, f1, 1.0, f3),
                                (f3, np.zeros((1, 1, 1), dtype=np.int64),
                                 np.zeros((1, 1), dtype=np.int64)))

    def _line(self, name: str) -> tuple:
        """A line as ``LineArrays.kernel_args``, its buffers and low-pass states stacked."""
        shared = [self.shared[f"{name}.{attr}"] for attr in LineArrays.FIXED]
        return (*shared, self.own[f"{name}.buf"], self.shared[f"{name}.lowpass"],
                self.own[f"{name}.state"])

    def adopt(self, i: int, sim: Simulator, bank: SensorBank) -> None:
        """Row i becomes ``sim``'s and ``bank``'s state: copied in, and they read and write it
        there."""
        arrays = sim.arrays()
        if set(arrays) != set(self.own) | set(self.shared) or any(
                arrays[name].shape != stack.shape[1:] for name, stack in self.own.items()) \
                or bank._ring.shape != self.bank["_ring"].shape[1:]:
            raise ValueError("a rig of another shape (preset, step, string model or sensor "
                             "profile) than the batch's")
        for name, fixed in self.shared.items():
            if not np.array_equal(arrays[name], fixed):
                raise ValueError("a distributed string unlike the batch's first")
        homes = sim._homes()
        pairs = [(*homes[name], stack) for name, stack in self.own.items()]
        pairs += [(bank, name, self.bank[name]) for name in _BANK]
        for owner, name, stack in pairs:
            row = stack[i]
            row[...] = getattr(owner, name)
            setattr(owner, name, row)
