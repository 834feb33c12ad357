"""``bag resim`` re-runs a session at the step the node used: the recorded ``step_s`` (the
largest divisor of the tick not above ``dt_s``), or ``dt_s`` itself for bags recorded before
the step divided the tick, which carry no ``step_s``. Either way the re-run is exact."""

from __future__ import annotations

import pytest
from sessionutil import session_bag

from drill_sim.session.resim import resimulate


@pytest.mark.parametrize("recorded_step", [True, False])
def test_resim_takes_the_step_the_session_ran_at(tmp_path, recorded_step):
    bag = tmp_path / "session"
    session_bag(bag, 300, rate_hz=100.0, recorded_step=recorded_step)
    result = resimulate(bag)
    assert result.samples == 300
    assert result.exact, result.explanation()
