"""The vector environment's step for every rig in one compiled call: each live rig's sample
into its series, its commands as the session holds them (``Rig.command``,
``Rig.command_motor_torque``), the kernel's advance over the control period (the lumped
string's or the distributed string's), its new sample as ``Rig.sample`` reads it (the forces
the means since the last sample), its sensors' reading (``SensorBank.measure``), the
observation (``RigEnv._observe``) and the reward (``RigEnv._reward``). The arithmetic is
theirs, in their order, so rig i equals a ``RigEnv`` to rounding.
"""

from __future__ import annotations

from numba import njit

from ..core import distributed_kernel as dk
from ..core import kernel as kn
from ..core.sensors import measure_kernel

# the rows of ``last`` and ``series`` (closed_loop.SERIES' order)
(F_TIME, F_BIT, F_TD_SPEED, F_SURFACE, F_MOTOR, F_OUTPUT, F_STUCK, F_DEPTH, F_TD_ANGLE,
 F_WOB) = range(10)
NF = 10
# the scales, in ``scales``: time [s], force [N], torque per radian [N m], length [m], the
# submerged weight [N], the step [s]
S_TIME, S_FORCE, S_TORQUE, S_LENGTH, S_WEIGHT, S_DT = range(6)
# the reward's weights, in ``weights``: speed, stick, saturation, torque rate; then h [s], the
# action's low and high
W_SPEED, W_STICK, W_SATURATION, W_RATE, W_H, W_LOW, W_HIGH = range(7)
# the sensors' channels (sensor_profile.CHANNELS): what the observation shows of them
M_SURFACE, M_TD_SPEED, M_MOTOR, M_HOOK, M_WOB, M_TOB, M_BIT = range(7)


@njit(cache=True)
def step_rigs(x, k, surf, p, c, acc, distributed, tz, tn, tf, tc, trel, toff, tbuf, tlp, tstate,
              az, an, af, ac, arel, aoff, abuf, alp, astate, scratch, slots, w_static,
              w_dynamic, w_kappa, sigma, w_cols, stuck, live, torque_mode, steps_per_tick, values,
              held_before, speed_set, hook, sample_k, last_k, window_k, speed_cmd, last, series,
              tob, scales, weights, obs, reward, window_now, s_par, s_state, s_istate, s_ring,
              s_noise, s_win, window_s, s_x, s_out, s_fresh, refill, exact, no_rows):
    """One control period of every live rig (module docstring). ``x`` .. ``acc``: the stacked
    kernel state; ``distributed``: the distributed string, whose lines' fixed arrays
    (``tz`` .. ``w_cols``, shared) and buffers, low-pass states, scratch, slots and stuck
    stations (each rig's) follow (the lumped string: any arrays of those types).
    ``values``: the actions as given, clipped here; ``held_before``: the commands the drives
    held (updated); ``sample_k`` (updated), ``last_k``: each rig's sample and its episode's
    last; ``window_now``: where a rig's metrics window starts now (the caller resets it);
    ``s_*``: the sensor banks' stacked arrays; ``refill``: where a rig's sensors want new
    noise; ``exact``: the ideal sensors, whose reading is the sample (not computed). Returns
    the first rig whose step the kernel refused, or -1. One function, no calls per rig but
    the kernels': a call passing these arrays cost ~0.3 us a rig."""
    ts, fn, cn = scales[S_TIME], scales[S_FORCE], scales[S_TORQUE]
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
        c[i, kn.C_W0] = (scales[S_WEIGHT] - hook[i, j]) / fn
        c[i, kn.C_OMEGA0] = speed * ts
        if torque_mode:
            c[i, kn.C_T_CMD] = held / cn
        else:
            x[i, kn.X_OMEGA_TD] = c[i, kn.C_OMEGA0]
        if distributed:
            dk.advance(x[i], k[i], surf[i], p[i], c[i], acc[i], tz, tn, tf, tc, trel, toff,
                       tbuf[i], tlp, tstate[i], az, an, af, ac, arel, aoff, abuf[i], alp,
                       astate[i], scratch[i], slots[i], w_static, w_dynamic, w_kappa, sigma,
                       w_cols, stuck[i], steps_per_tick, no_rows, 1, 0)
        elif torque_mode:
            kn.advance_drive(x[i], k[i], surf[i], p[i], c[i], acc[i], steps_per_tick, no_rows,
                             1, 0)
        else:
            kn.advance_kinematic(x[i], k[i], surf[i], p[i], c[i], acc[i], steps_per_tick,
                                 no_rows, 1, 0)
        if k[i, kn.K_REFUSED]:
            return i
        j += 1
        sample_k[i] = j
        # the sample (Rig.sample, Simulator.take_force_sums)
        sum_w = x[i, kn.X_SUM_W]
        sum_t = x[i, kn.X_SUM_T]
        n = k[i, kn.K_STEPS] - k[i, kn.K_SAMPLED]
        h = p[i, kn.P_H]
        acc[i, kn.A_W] += h * sum_w
        acc[i, kn.A_T] += h * sum_t
        x[i, kn.X_SUM_W] = 0.0
        x[i, kn.X_SUM_T] = 0.0
        k[i, kn.K_SAMPLED] = k[i, kn.K_STEPS]
        time_s = k[i, kn.K_STEPS] * scales[S_DT]
        last[F_TIME, i] = time_s
        last[F_BIT, i] = x[i, kn.X_OMEGA] / ts
        last[F_SURFACE, i] = x[i, kn.X_TS] * cn
        if torque_mode:
            last[F_TD_SPEED, i] = x[i, kn.X_OMEGA_TD] / ts
            last[F_MOTOR, i] = x[i, kn.X_TM] * cn
        else:
            last[F_TD_SPEED, i] = speed_cmd[i]
            last[F_MOTOR, i] = x[i, kn.X_TS] * cn
        stuck_now = k[i, kn.K_REGIME] == kn.REGIME_STUCK
        last[F_STUCK, i] = 1.0 if stuck_now else 0.0
        last[F_DEPTH, i] = x[i, kn.X_U] * scales[S_LENGTH]
        last[F_TD_ANGLE, i] = x[i, kn.X_PHI_TD]
        last[F_WOB, i] = (0.0 + sum_w * fn) / n
        tob[i] = (0.0 + sum_t * cn) / n
        window_now[i] = j == window_k[i]
        # the sensors (SensorBank.measure: the sample's channels in CHANNELS' order)
        m = s_x[i]
        m[M_SURFACE] = last[F_SURFACE, i]
        m[M_TD_SPEED] = last[F_TD_SPEED, i]
        m[M_MOTOR] = last[F_MOTOR, i]
        m[M_HOOK] = hook[i, j - 1]
        m[M_WOB] = last[F_WOB, i]
        m[M_TOB] = tob[i]
        m[M_BIT] = last[F_BIT, i]
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
        obs[i, 0] = out[M_TD_SPEED]
        obs[i, 1] = out[M_MOTOR]
        obs[i, 2] = out[M_SURFACE]
        obs[i, 3] = out[M_HOOK]
        obs[i, 4] = target
        dev = ((last[F_BIT, i] - target) / max(target, 1e-3)) ** 2
        rate = 0.0
        if torque_mode:
            rate = (abs(held - held_before[i]) / weights[W_H] / 1e6) ** 2
        on_limit = values[i] != held or held == low or held == high
        reward[i] = -(weights[W_SPEED] * dev + weights[W_STICK] * (1.0 if stuck_now else 0.0)
                      + weights[W_SATURATION] * (1.0 if on_limit else 0.0)
                      + weights[W_RATE] * rate)
        held_before[i] = held
    return -1
