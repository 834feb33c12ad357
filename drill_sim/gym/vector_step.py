"""The vector environment's step for every rig in one compiled call: each live rig's sample
into its series, its commands as the session holds them (``Rig.command``,
``Rig.command_motor_torque``), the kernel's advance over the control period (the lumped
string's or the distributed string's), its new sample as ``Rig.sample`` reads it (the forces
the means since the last sample), its sensors' reading (``SensorBank.measure``), the
observation (``RigEnv._observe``) and the reward (``RigEnv._reward``). It composes the
compiled helpers those call (``core.rig_step``, ``sensors.measure_kernel``, ``payoff``), in
their order, so rig i equals a ``RigEnv``.
"""

from __future__ import annotations

from numba import njit

from ..core import bit_rock, rig_step, sensors, stick_slip
from ..core import distributed_kernel as dk
from ..core import kernel as kn
from ..core import state_layout as sl
from ..core.numba_cache import follow
from ..core.rig_step import (
    R_BIT,
    R_DEPTH,
    R_MOTOR,
    R_REGIME,
    R_SURFACE,
    R_TD_ANGLE,
    R_TD_SPEED,
    R_TIME,
    mean_forces,
    sample_into,
    take_force_sums,
    write_commands,
    write_motor_torque,
)
from ..core.sensors import (
    M_BIT,
    M_HOOK,
    M_MOTOR,
    M_SURFACE,
    M_TD_SPEED,
    M_TOB,
    M_WOB,
    measure_kernel,
)
from . import payoff
from .payoff import W_HIGH, W_LOW, observe_into, reward_of

# the cache follows every file whose code the step compiles in (the kernels it calls included)
follow(__file__, *(m.__file__ for m in (kn, dk, bit_rock, sl, rig_step, sensors, stick_slip,
                                        payoff)))

# the rows of ``last`` and ``series`` (closed_loop.SERIES' order)
(F_TIME, F_BIT, F_TD_SPEED, F_SURFACE, F_MOTOR, F_OUTPUT, F_STUCK, F_DEPTH, F_TD_ANGLE,
 F_WOB) = range(10)
NF = 10


@njit(cache=True)
def step_rigs(rigs, string, schedule, record, constants, sensors, outputs):
    """One control period of every live rig (module docstring); returns the first rig whose
    step the kernel refused, or -1. One function, no calls per rig but the compiled helpers':
    a call passing these arrays cost ~0.3 us a rig.

    Parameters, each a tuple:
    - ``rigs``: the stacked kernel arrays (x, k, surface, p, c, acc);
    - ``string``: (distributed, torsion, axial, wall, work): the distributed string's lines
      (``LineArrays.kernel_args``, buffers and low-pass states stacked), the wall's friction and
      each rig's work arrays (scratch, slots, held stations), as ``distributed_kernel.advance``
      takes them (the lumped string: any arrays of those types);
    - ``schedule``: (live, torque_mode, steps_per_tick, values, held_before, speed_set, hook,
      sample_k, last_k, window_k, speed_cmd): which rigs step, the drive's mode, the steps a
      tick, the actions as given (clipped here), the commands the drives held (updated), each
      rig's speed set-point and hook load by sample, its sample (updated), its episode's last,
      its metrics window's start, its held speed command (updated);
    - ``record``: (last, series, tob): each rig's last sample (``closed_loop.SERIES``), its
      series, its last TOB;
    - ``constants``: (scales, weights): the rows ``rig_step.SCALE_FIELDS`` and
      ``payoff.WEIGHT_FIELDS``;
    - ``sensors``: (par, state, istate, ring, noise, window, window_s, x, out, fresh, refill,
      exact): the sensor banks' stacked arrays, where a rig's sensors want new noise, and
      whether the sensors are ideal (their reading is the sample, not computed);
    - ``outputs``: (obs, reward, window_now, no_rows, row): the observations, rewards, where a
      rig's metrics window starts now (the caller resets it), no output rows, a scratch
      sample (``rig_step.SAMPLE_FIELDS``).
    """
    x, k, surf, p, c, acc = rigs
    distributed, torsion, axial, wall, work = string
    (live, torque_mode, steps_per_tick, values, held_before, speed_set, hook, sample_k, last_k,
     window_k, speed_cmd) = schedule
    last, series, tob = record
    scales, weights = constants
    (s_par, s_state, s_istate, s_ring, s_noise, s_win, window_s, s_x, s_out, s_fresh, refill,
     exact) = sensors
    obs, reward, window_now, no_rows, row = outputs
    tz, tn, tf, tc, trel, toff, tbuf, tlp, tstate = torsion
    az, an, af, ac, arel, aoff, abuf, alp, astate = axial
    scratch, slots, stuck = work
    low, high = weights[W_LOW], weights[W_HIGH]
    for i in range(x.shape[0]):
        window_now[i] = False
        refill[i] = False
        if not live[i]:
            continue
        # the sample answered into the series; the commands (Rig.command, .command_motor_torque)
        j = sample_k[i]
        held = min(max(values[i], low), high)
        for f in range(NF):
            series[f, i, j] = last[f, i]
        series[F_OUTPUT, i, j] = held
        speed = speed_set[i, j] if torque_mode else held
        speed_cmd[i] = speed
        xi, ki, ci, ai = x[i], k[i], c[i], acc[i]      # each rig's views, made once
        write_commands(xi, ci, not torque_mode, speed, hook[i, j], scales)
        if torque_mode:
            write_motor_torque(ci, held, scales)
        if distributed:
            dk.advance(xi, ki, surf[i], p[i], ci, ai,
                       (tz, tn, tf, tc, trel, toff, tbuf[i], tlp, tstate[i]),
                       (az, an, af, ac, arel, aoff, abuf[i], alp, astate[i]), wall,
                       (scratch[i], slots[i], stuck[i]), steps_per_tick, no_rows, 1, 0)
        elif torque_mode:
            kn.advance_drive(xi, ki, surf[i], p[i], ci, ai, steps_per_tick, no_rows, 1, 0)
        else:
            kn.advance_kinematic(xi, ki, surf[i], p[i], ci, ai, steps_per_tick, no_rows, 1, 0)
        if ki[sl.K_REFUSED]:
            return i
        j += 1
        sample_k[i] = j
        # the sample (Rig.sample)
        sum_w, sum_t, n = take_force_sums(xi, ki, ai, p[i, sl.P_H])
        wob, tob[i] = mean_forces(sum_w, sum_t, n, 0.0, 0.0, scales)
        sample_into(xi, ki, not torque_mode, speed, scales, row)
        time_s = row[R_TIME]
        last[F_TIME, i] = time_s
        last[F_BIT, i] = row[R_BIT]
        last[F_SURFACE, i] = row[R_SURFACE]
        last[F_TD_SPEED, i] = row[R_TD_SPEED]
        last[F_MOTOR, i] = row[R_MOTOR]
        stuck_now = row[R_REGIME] == kn.REGIME_STUCK
        last[F_STUCK, i] = 1.0 if stuck_now else 0.0
        last[F_DEPTH, i] = row[R_DEPTH]
        last[F_TD_ANGLE, i] = row[R_TD_ANGLE]
        last[F_WOB, i] = wob
        window_now[i] = j == window_k[i]
        # the sensors (SensorBank.measure: the sample's channels in CHANNELS' order)
        m = s_x[i]
        m[M_SURFACE] = row[R_SURFACE]
        m[M_TD_SPEED] = row[R_TD_SPEED]
        m[M_MOTOR] = row[R_MOTOR]
        m[M_HOOK] = hook[i, j - 1]
        m[M_WOB] = wob
        m[M_TOB] = tob[i]
        m[M_BIT] = row[R_BIT]
        out = s_out[i]
        if exact:
            for ch in range(M_BIT + 1):
                out[ch] = m[ch]
        else:
            refill[i] = measure_kernel(time_s, m, s_par[i], s_state[i], s_istate[i],
                                       s_ring[i], s_noise[i], s_win[i], window_s, out,
                                       s_fresh[i])
        # what the policy sees and is paid (RigEnv._observe, RigEnv._reward)
        target = speed_set[i, min(j, last_k[i])]
        observe_into(out[M_TD_SPEED], out[M_MOTOR], out[M_SURFACE], out[M_HOOK], target, obs[i])
        reward[i] = reward_of(row[R_BIT], target, stuck_now, values[i], held, held_before[i],
                              torque_mode, weights)
        held_before[i] = held
    return -1
