"""``Trajectory.to_si``: the offline run's samples in SI agree with the scales and the Rig."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from drill_sim.core import Rig, SITrajectory


@pytest.fixture(scope="module")
def steady_run(base):
    rig = Rig(base.rig)
    rig.start_steady(base.top_drive_speed_rad_s, base.hook_load_n, perturbation=1e-3)
    dt = rig.sim.dt          # a whole number of rows, the last one at the end of the run
    return rig, rig.sim.run(20_000 * dt, output_interval=100 * dt)


def test_to_si_scales_every_array(base, steady_run):
    rig, tr = steady_run
    sc, n = rig.scales, rig.groups.n
    si = tr.to_si(sc, n)
    assert isinstance(si, SITrajectory)
    expected = {"time_s": tr.tau * sc.time_s, "bit_speed_rad_s": tr.omega / sc.time_s,
                "rop_m_s": tr.v * sc.length_m / sc.time_s, "wob_n": tr.w * sc.force_n,
                "tob_nm": tr.t * sc.stiffness_nm_per_rad,
                "surface_torque_nm": tr.ts * sc.stiffness_nm_per_rad,
                "depth_of_cut_m": tr.delta_n * n * sc.length_m, "bit_depth_m": tr.u * sc.length_m,
                "bit_angle_rad": tr.phi, "top_drive_speed_rad_s": tr.omega_td / sc.time_s,
                "available_weight_n": tr.w0 * sc.force_n,
                "top_drive_speed_setpoint_rad_s": tr.omega0 / sc.time_s,
                "motor_torque_nm": tr.motor_torque * sc.stiffness_nm_per_rad}
    for name, value in expected.items():
        np.testing.assert_allclose(getattr(si, name), value, rtol=1e-12, err_msg=name)
    assert np.array_equal(si.stuck, tr.stuck) and np.array_equal(si.off_bottom, tr.off_bottom)
    assert {f.name for f in dataclasses.fields(si)} == set(expected) | {"stuck", "off_bottom"}
    # the commands come back as given, in SI; the kinematic top drive turns at its command
    np.testing.assert_allclose(si.top_drive_speed_rad_s, base.top_drive_speed_rad_s, rtol=1e-12)
    assert np.array_equal(si.top_drive_speed_setpoint_rad_s, si.top_drive_speed_rad_s)
    np.testing.assert_allclose(si.available_weight_n, 1e3 * base.weight_on_bit_kn, rtol=1e-9)
    assert si.time_s[-1] == pytest.approx(20_000 * rig.dt_s, rel=1e-9)


def test_to_si_agrees_with_the_rigs_own_sample(steady_run):
    rig, tr = steady_run
    si, now = tr.to_si(rig.scales, rig.groups.n), rig.sample()
    assert si.time_s[-1] == pytest.approx(now.time_s, abs=rig.dt_s)
    # the state at the last row; WOB and TOB are means over an interval (a row's, a sample's),
    # which differ here, so they are checked against the scales above
    for name in ("bit_speed_rad_s", "rop_m_s", "surface_torque_nm",
                 "depth_of_cut_m", "bit_depth_m", "bit_angle_rad", "top_drive_speed_rad_s",
                 "top_drive_speed_setpoint_rad_s", "motor_torque_nm"):
        assert getattr(si, name)[-1] == pytest.approx(getattr(now, name), rel=1e-9), name
    assert math.isclose(si.wob_n.mean(), 1e5, rel_tol=0.02)      # steady start: ~100 kN
