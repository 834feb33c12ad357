"""The vector environment's step for every rig in one compiled call: each live rig's sample
into its series, its commands as the session holds them (``Rig.command``,
``Rig.command_motor_torque``), the kernel's advance over the control period, its new sample as
``Rig.sample`` reads it (the forces the means since the last sample), the observation
(``RigEnv._observe``) and the reward (``RigEnv._reward``). The arithmetic is theirs, in their
order, so rig i equals a ``RigEnv`` to rounding.
"""

from __future__ import annotations

from numba import njit

from ..core import kernel as kn

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


@njit(cache=True)
def step_rigs(x, k, surf, p, c, acc, live, torque_mode, steps_per_tick, values, held_before,
              speed_set, hook, sample_k, last_k, window_k, speed_cmd, last, series, tob, scales,
              weights, obs, reward, window_now, no_rows):
    """One control period of every live rig (module docstring). ``values``: the actions as
    given, clipped here; ``held_before``: the commands the drives held (updated); ``sample_k``
    (updated) and ``last_k``: each rig's sample index and its episode's last; ``window_now``:
    set where a rig's metrics window starts at this sample (the caller resets it). Returns the
    first rig whose step the kernel refused, or -1."""
    ts, fn, cn, ln = scales[S_TIME], scales[S_FORCE], scales[S_TORQUE], scales[S_LENGTH]
    low, high = weights[W_LOW], weights[W_HIGH]
    for i in range(x.shape[0]):
        window_now[i] = False
        if not live[i]:
            continue
        j = sample_k[i]
        value = values[i]
        held = min(max(value, low), high)
        for f in range(NF):
            series[f, i, j] = last[f, i]
        series[F_OUTPUT, i, j] = held
        speed = speed_set[i, j] if torque_mode else held
        speed_cmd[i] = speed
        c[i, kn.C_W0] = (scales[S_WEIGHT] - hook[i, j]) / fn
        c[i, kn.C_OMEGA0] = speed * ts
        if torque_mode:
            c[i, kn.C_T_CMD] = held / cn
            kn.advance_drive(x[i], k[i], surf[i], p[i], c[i], acc[i], steps_per_tick, no_rows,
                             1, 0)
        else:
            x[i, kn.X_OMEGA_TD] = c[i, kn.C_OMEGA0]
            kn.advance_kinematic(x[i], k[i], surf[i], p[i], c[i], acc[i], steps_per_tick,
                                 no_rows, 1, 0)
        if k[i, kn.K_REFUSED]:
            return i
        j += 1
        sample_k[i] = j
        # the sample (Rig.sample, Simulator.take_force_sums)
        sum_w, sum_t = x[i, kn.X_SUM_W], x[i, kn.X_SUM_T]
        n = k[i, kn.K_STEPS] - k[i, kn.K_SAMPLED]
        h = p[i, kn.P_H]
        acc[i, kn.A_W] += h * sum_w
        acc[i, kn.A_T] += h * sum_t
        x[i, kn.X_SUM_W] = 0.0
        x[i, kn.X_SUM_T] = 0.0
        k[i, kn.K_SAMPLED] = k[i, kn.K_STEPS]
        last[F_TIME, i] = k[i, kn.K_STEPS] * scales[S_DT]
        last[F_BIT, i] = x[i, kn.X_OMEGA] / ts
        last[F_SURFACE, i] = x[i, kn.X_TS] * cn
        if torque_mode:
            last[F_TD_SPEED, i] = x[i, kn.X_OMEGA_TD] / ts
            last[F_MOTOR, i] = x[i, kn.X_TM] * cn
        else:
            last[F_TD_SPEED, i] = speed_cmd[i]
            last[F_MOTOR, i] = x[i, kn.X_TS] * cn
        stuck = k[i, kn.K_REGIME] == kn.REGIME_STUCK
        last[F_STUCK, i] = 1.0 if stuck else 0.0
        last[F_DEPTH, i] = x[i, kn.X_U] * ln
        last[F_TD_ANGLE, i] = x[i, kn.X_PHI_TD]
        last[F_WOB, i] = (0.0 + sum_w * fn) / n
        tob[i] = (0.0 + sum_t * cn) / n
        window_now[i] = j == window_k[i]
        # what the policy sees and is paid
        target = speed_set[i, min(j, last_k[i])]
        obs[i, 0] = last[F_TD_SPEED, i]
        obs[i, 1] = last[F_MOTOR, i]
        obs[i, 2] = last[F_SURFACE, i]
        obs[i, 3] = hook[i, j - 1]
        obs[i, 4] = target
        dev = ((last[F_BIT, i] - target) / max(target, 1e-3)) ** 2
        rate = 0.0
        if torque_mode:
            rate = (abs(held - held_before[i]) / weights[W_H] / 1e6) ** 2
        on_limit = value != held or held == low or held == high
        reward[i] = -(weights[W_SPEED] * dev + weights[W_STICK] * (1.0 if stuck else 0.0)
                      + weights[W_SATURATION] * (1.0 if on_limit else 0.0)
                      + weights[W_RATE] * rate)
        held_before[i] = held
    return -1
