"""The closed-loop roots of the distributed string with a law at its top (``control.impedance``
through ``string_modes``) against the simulation: each law stepped every 10 ms on the rig off
bottom, a set-point step, and the poles of the bit speed's ring-down estimated from the
samples alone (matrix pencil): frequency and growth rate of the lowest modes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from drill_sim.control import make_law
from drill_sim.control.evaluation import ideal_measurement
from drill_sim.control.impedance import top_boundary
from drill_sim.control.reference import reference_gains
from drill_sim.control.supervisor import Supervisor
from drill_sim.control.tuning import pipe_impedance
from drill_sim.core import DEFAULT_DT
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.presets import load_preset
from drill_sim.core.rig import Rig
from drill_sim.core.stability_distributed import string_modes

H = 0.01
J = 2900.0


def _pencil_poles(y: np.ndarray, dt: float, order: int) -> np.ndarray:
    """Poles s [1/s] of a sum of ``order`` damped exponentials fitted to samples ``y`` (the
    matrix pencil: the signal's Hankel matrix, its leading singular vectors shifted by one)."""
    rows = y.size // 2
    hankel = np.array([y[i:i + rows + 1] for i in range(y.size - rows)])
    v = np.linalg.svd(hankel, full_matrices=False)[2][:order].conj().T
    z = np.linalg.eigvals(np.linalg.pinv(v[:-1]) @ v[1:])
    return np.log(z.astype(complex)) / dt


def _simulated_poles(preset, law: str) -> np.ndarray:
    rig = Rig(preset.rig, 1e-4, top_drive=replace(preset.top_drive, top_drive_mode="torque"),
              string_model="distributed", geometry=preset.string)
    rig.start_at_rest(0.5)
    rig.command(0.0, preset.rig.submerged_weight_n)      # the hook holds it: off bottom
    gains = reference_gains(law, preset, J, string_model="distributed")
    sup = Supervisor(H, pipe_impedance(preset), J, law, gains, speed_set_rad_s=0.0)
    sup.last_output = 0.0
    sup.set_speed(0.5)
    bit = []
    for _ in range(1600):
        rig.command_motor_torque(sup.step(ideal_measurement(rig.sample())))
        rig.advance_steps(round(H / 1e-4))
        bit.append(rig.sample().bit_speed_rad_s)
    ring = np.array(bit[100::2]) - 0.5                      # from 1 s, every 20 ms
    poles = _pencil_poles(ring, 2 * H, 12)
    return poles[poles.imag > 1.0]


def _predicted_poles(preset, law: str) -> list[complex]:
    rig = preset.rig
    gains = reference_gains(law, preset, J, string_model="distributed")
    boundary = top_boundary(make_law(law, H, pipe_impedance(preset), J, **gains))
    ts, c = rig.scales.time_s, rig.scales.stiffness_nm_per_rad

    def top(s):
        k, lag = boundary(s / ts)
        return k / c, lag
    waves = geometry_waves(rig, preset.string, DEFAULT_DT)       # the simulation's own lines
    drive = preset.top_drive.groups(rig.scales, rig.bha_inertia_kg_m2)
    modes = string_modes(waves, rig.groups.psi, drive, 3, top=top)
    assert modes.complete
    return [m.root / ts for m in modes.torsional]


@pytest.mark.parametrize(("law", "count"), [("stiff_pi", 3), ("soft_speed", 3),
                                            ("z_torque", 2)])
def test_the_closed_loop_roots_are_the_simulations(law, count):
    """The lowest modes' frequencies to 1 % and growth rates to 10 % (measured: stiff PI and
    SoftSpeed within 1 %, Z-Torque's second 6 %; its third mode, little in the bit's speed and
    beside the law's own well-damped root at 3.6 Hz, is not resolved by the fit)."""
    preset = load_preset("base")
    simulated = _simulated_poles(preset, law)
    for root in _predicted_poles(preset, law)[:count]:
        near = simulated[np.argmin(np.abs(simulated - root))]
        assert near.imag == pytest.approx(root.imag, rel=0.01), (law, root, near)
        assert near.real == pytest.approx(root.real, rel=0.10), (law, root, near)

