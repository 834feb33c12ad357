"""The named scenario set ``drill_sim control`` scores every law on (msg_docs/control.md).

Around base's stick-slip region (60 rpm / 100 kN sticks under a stiff drive; 150 rpm does not
stick; below W0 ≈ 71 kN = λ F* the bit does not cut): a grid of rpm × WOB, a WOB step into
harder drilling, a speed ramp down into the region, and a controller switched on in
established stick-slip (the before/after).
"""

from __future__ import annotations

from ..core.parameters import ParameterError
from ..session.scenario import Scenario, load_scenario, scenario_names

GRID_RPM = (40.0, 60.0, 90.0)
GRID_WOB_KN = (80.0, 100.0, 120.0)


def grid(rpms: tuple[float, ...] = GRID_RPM,
         wobs_kn: tuple[float, ...] = GRID_WOB_KN) -> list[Scenario]:
    """Steady set-points, 40 s each, metrics over the last 20 s."""
    return [Scenario.steady(r, w, name=f"grid_{r:g}rpm_{w:g}kN", duration_s=40.0,
                            window_start_s=20.0) for r in rpms for w in wobs_kn]


def wob_step() -> Scenario:
    """60 rpm; W0 80 → 120 kN in 1 s at 20 s; metrics over 25–50 s."""
    return Scenario.of_points("wob_step", ((0.0, 60.0),),
                              ((0.0, 80.0), (20.0, 80.0), (21.0, 120.0)),
                              duration_s=50.0, window_start_s=25.0)


def speed_ramp() -> Scenario:
    """100 kN; 120 → 40 rpm from 10 s to 40 s; metrics over 20–50 s (through the region)."""
    return Scenario.of_points("speed_ramp", ((0.0, 120.0), (10.0, 120.0), (40.0, 40.0)),
                              ((0.0, 100.0),), duration_s=50.0, window_start_s=20.0)


def switch_on() -> Scenario:
    """60 rpm / 100 kN; the drive's stiff loop until 20 s (stick-slip established), then the
    law; metrics over 35–60 s."""
    return Scenario.steady(60.0, 100.0, name="switch_on", duration_s=60.0, window_start_s=35.0,
                           switch_on_s=20.0)


SETS = {
    "grid": grid,
    "wob_step": lambda: [wob_step()],
    "speed_ramp": lambda: [speed_ramp()],
    "switch_on": lambda: [switch_on()],
}
STANDARD = ("grid", "wob_step", "speed_ramp", "switch_on")


def named(names: tuple[str, ...] | list[str]) -> list[Scenario]:
    """The scenarios of these set names, in order (``standard``: all of them); a name that is
    no set is a scenario the rig plays (shipped, ``controller_on``, or a YAML file), the very
    experiment a node runs with ``scenario:=``."""
    out: list[Scenario] = []
    for name in names:
        for part in (STANDARD if name == "standard" else (name,)):
            if part in SETS:
                out.extend(SETS[part]())
            elif part in scenario_names() or part.endswith((".yaml", ".yml")):
                out.append(load_scenario(part))
            else:
                raise ParameterError(f"scenario set {part!r} is unknown: expected one of "
                                     f"standard, {', '.join(SETS)}, a rig scenario "
                                     f"({', '.join(scenario_names())}) or a scenario YAML")
    return out
