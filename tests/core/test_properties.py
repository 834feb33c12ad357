"""10. Property-based: random valid groups and command sequences keep the state sane."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from numba.core.runtime import rtsys

from drill_sim.core import Groups, ParameterError, Simulator

groups_st = st.builds(Groups, n=st.integers(1, 8), psi=st.floats(0.5, 60.0),
                      lam=st.floats(0.0, 15.0), beta=st.floats(0.0, 2.0))
commands_st = st.lists(st.tuples(st.floats(-5.0, 25.0), st.floats(0.0, 6.0)),
                       min_size=1, max_size=6)


@settings(max_examples=60, deadline=None)
@given(groups=groups_st, commands=commands_st, start_steady=st.booleans(),
       gap=st.floats(0.0, 5.0))
@example(groups=Groups(1, 1.0, 5e-324, 0.0), commands=[(0.0, 1.0)], start_steady=False,
         gap=0.0)                       # h psi lambda underflows to 0 at an axial stick
def test_random_parameters_and_commands(groups, commands, start_steady, gap):
    sim = Simulator(groups, 2e-3)
    w_first, om_first = commands[0]
    if start_steady and w_first > groups.lam and om_first > 0.05:
        sim.start_steady(w_first, om_first, 0.01)
    else:
        sim.start_at_rest(gap)
    surface_id, size = id(sim._surf), sim._surf.size
    for w0, omega0 in commands:
        sim.set_commands(w0, omega0)
        before = sim.surface
        tr = sim.run(5.0, output_interval=sim.dt)
        rows = np.column_stack([tr.u, tr.v, tr.phi, tr.omega, tr.w, tr.t, tr.ts, tr.delta_n])
        assert np.all(np.isfinite(rows))
        assert np.all(tr.omega[~tr.off_bottom] >= 0.0)      # no backward rotation in contact
        assert np.all(tr.w >= 0.0)                          # the rock only pushes
        assert np.all(sim.surface >= before)                # the hole never fills in
        assert sim.hole_bottom == pytest.approx(max(sim.surface.max(), 0.0))
        # a stuck bit never moves down (it may coast up: the one-way hold); rows carry the mean
        # force over their interval, so "resting on rock" is checked on the step's own state
        assert np.all(tr.v[tr.stuck] <= 0.0)
        end = sim.state()
        assert not (end.stuck and end.w > 0.0) or end.v == 0.0   # resting on rock: still
    assert id(sim._surf) == surface_id and sim._surf.size == size


def test_no_allocation_per_step(base_groups, base_commands):
    """Fixed memory: the kernel's heap traffic per call (numba wrapping the argument arrays)
    does not depend on how many steps the call takes."""
    sim = Simulator(base_groups)
    sim.start_steady(*base_commands, 1e-3)
    sim.advance(1000)                                       # compiled and warm

    def allocations(steps: int) -> int:
        before = rtsys.get_allocation_stats().alloc
        for _ in range(50):
            sim.advance(steps)
        return rtsys.get_allocation_stats().alloc - before

    assert allocations(10) == allocations(100_000)


def test_bad_commands_leave_the_state_untouched(base_groups, base_commands):
    sim = Simulator(base_groups)
    sim.start_steady(*base_commands)
    sim.advance(100)
    snapshot = sim.state()
    for w0, om in ((math.nan, 1.0), (1.0, math.inf), (1.0, -0.5), ("x", 1.0)):
        with pytest.raises(ParameterError):
            sim.set_commands(w0, om)
    assert sim.commands == pytest.approx(base_commands)
    assert sim.state() == snapshot
