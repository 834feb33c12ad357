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

from . import distributed_kernel as dk
from . import kernel as kn
from .sensors import SensorBank
from .simulator import Simulator

# the simulator's arrays that are each rig's own (a distributed string adds its lines')
_STATE = ("_x", "_k", "_surf", "_p", "_c", "_acc")
_LINE_STATE = ("buf", "state")
_LINE_FIXED = ("z", "n", "f", "c", "rel", "off", "lowpass")
_BANK = ("_par", "_state", "_istate", "_ring", "_noise", "_window", "_x", "_out", "_fresh")


def _stacked(n: int, a: np.ndarray) -> np.ndarray:
    return np.zeros((n, *a.shape), dtype=a.dtype)


class RigBatch:
    """The stacked state of ``n`` rigs shaped as ``sim`` and ``bank`` (the first rig's);
    ``lines_args``: a distributed string's line arrays in ``distributed_kernel.advance``'s
    order (per rig stacked where a rig's own), or arrays of their types for a lumped one."""

    def __init__(self, n: int, sim: Simulator, bank: SensorBank) -> None:
        self.distributed = hasattr(sim, "waves")
        self.no_rows = np.zeros((0, dk.NOD if self.distributed else kn.NO))
        self.state = {name: _stacked(n, getattr(sim, name)) for name in _STATE}
        self.x, self.k, self.surf, self.p, self.c, self.acc = (self.state[s] for s in _STATE)
        self.bank = {name: _stacked(n, getattr(bank, name)) for name in _BANK}
        self.window_s = bank._window_s
        if self.distributed:
            self.lines = {(w, name): _stacked(n, getattr(getattr(sim, "_" + w), name))
                          for w in "ta" for name in _LINE_STATE}
            self.rest = {"_scratch": _stacked(n, sim._scratch),
                         "_slots": _stacked(n, sim._slots), "_stuck": _stacked(n, sim._stuck)}
            self.fixed = {(w, name): getattr(getattr(sim, "_" + w), name)
                          for w in "ta" for name in _LINE_FIXED}
            self.wall = sim._wall
            line = [[self.fixed[(w, name)] for name in _LINE_FIXED[:6]]
                    + [self.lines[(w, "buf")], self.fixed[(w, "lowpass")],
                       self.lines[(w, "state")]] for w in "ta"]
            self.lines_args = (*line[0], *line[1], self.rest["_scratch"], self.rest["_slots"],
                               *self.wall, self.rest["_stuck"])
        else:                                # the distributed arguments' types, never read
            f1, i1 = np.zeros(1), np.zeros(1, dtype=np.int64)
            f2, f3 = np.zeros((1, 1)), np.zeros((1, 1, 1))
            one = (f1, i1, f1, f1, f1, i1, f2, f2, f3)
            self.lines_args = (*one, *one, f3, np.zeros((1, 1, 1), dtype=np.int64), f1, f1, f1,
                               1.0, f3, np.zeros((1, 1), dtype=np.int64))

    def adopt(self, i: int, sim: Simulator, bank: SensorBank) -> None:
        """Row i becomes ``sim``'s and ``bank``'s state: copied in, and they read and write it
        there."""
        if hasattr(sim, "waves") != self.distributed or sim._surf.shape != self.surf.shape[1:] \
                or bank._ring.shape != self.bank["_ring"].shape[1:]:
            raise ValueError("a rig of another shape (preset, step, string model or sensor "
                             "profile) than the batch's")
        if self.distributed:
            for (w, name), fixed in self.fixed.items():
                if not np.array_equal(getattr(getattr(sim, "_" + w), name), fixed):
                    raise ValueError("a distributed string unlike the batch's first")
        pairs = [(sim, name, self.state[name]) for name in _STATE]
        pairs += [(bank, name, self.bank[name]) for name in _BANK]
        if self.distributed:
            pairs += [(getattr(sim, "_" + w), name, self.lines[(w, name)])
                      for w in "ta" for name in _LINE_STATE]
            pairs += [(sim, name, stack) for name, stack in self.rest.items()]
        for owner, name, stack in pairs:
            row = stack[i]
            row[...] = getattr(owner, name)
            setattr(owner, name, row)
