"""The numba stepping kernel: fixed step, exact set-valued bit-rock laws, fixed memory.

Scheme (a Moreau midpoint time-stepping scheme, second order in smooth phases):

1. drift half a step: u_m = u + h/2 v, phi_m = phi + h/2 omega, phi_td_m = phi_td + h/2 omega0;
2. evaluate the depth of cut delta = u_m - S(phi_m) on the rock surface left by earlier passes;
3. solve the set-valued laws of MODEL.md section 2.2 *implicitly* for the end-of-step velocities
   (the wear-flat factor g from the sign of v+, stick from the sign of omega+, the rock reaction
   from the sign of v+ while stuck): each is a one-dimensional complementarity problem solved
   exactly by trying its branches, so no law is ever regularised;
4. drift the second half with the new velocities and let the blades sweep the surface:
   S(theta) <- max(S(theta), u) at every grid node passed.

The surface is an array of N = 2^m nodes over one sector 2*pi/n, linear between nodes. All state
lives in preallocated arrays indexed by the constants below, so advancing allocates nothing.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# float state x
X_TAU, X_U, X_V, X_PHI, X_OMEGA, X_PHI_TD = 0, 1, 2, 3, 4, 5
X_S_BEHIND = 6      # surface value of the last node passed, from before this pass
X_SINCE_STICK = 7   # time since the bit was last stuck [t*]
X_W, X_T = 8, 9     # weight and torque on bit during the last step [F*], [C]
X_TS = 10           # string torque phi_td - phi at the end of the last step [C]
X_DELTA = 11        # depth of cut per blade during the last step [L*]
X_G = 12            # wear-flat contact factor during the last step [-]
X_HOLE = 13         # deepest point of the rock surface, max of S [L*]
NX = 14

# integer state k
K_LAST = 0          # absolute index of the last surface node the blades passed
K_REGIME = 1        # REGIME_* of the last step
K_STEPS = 2         # steps taken since the start
NK = 3

REGIME_ROTATING, REGIME_STUCK, REGIME_OFF_BOTTOM = 0, 1, 2

# parameters p
P_N, P_PSI, P_LAM, P_BETA, P_H, P_DTHETA, P_INV_DTHETA = range(7)
NP = 7

# commands c (zero-order hold between calls)
C_W0, C_OMEGA0, C_V_MIN = 0, 1, 2   # C_V_MIN: lowest axial velocity (hoisting-speed limit)
NC = 3

# accumulators a, integrals over the metrics window
(A_TIME, A_OMEGA, A_OMEGA_MIN, A_OMEGA_MAX, A_W, A_T, A_TS, A_V, A_STICK_TIME, A_BOUNCE_TIME,
 A_WORK_TOP_DRIVE, A_WORK_WEIGHT, A_WORK_HOIST, A_DISSIPATED_ROT, A_DISSIPATED_AX,
 A_W0, A_OMEGA0) = range(17)
NA = 17

# output columns
(O_TAU, O_U, O_V, O_PHI, O_OMEGA, O_PHI_TD, O_W, O_T, O_TS, O_DELTA, O_REGIME, O_W0, O_OMEGA0,
 O_G) = range(14)
NO = 14


@njit(cache=True, inline="always")
def _surface_at(surf, mask, phi, inv_dtheta, k_last, s_behind):
    """S(phi) before the current pass, linear between nodes."""
    pos = phi * inv_dtheta
    km = math.floor(pos)
    frac = pos - km
    k0 = np.int64(km)
    if k0 == k_last:
        s0 = s_behind          # node k_last was already overwritten by this pass
    else:
        s0 = surf[k0 & mask]
    s1 = surf[(k0 + 1) & mask]
    return s0 + frac * (s1 - s0)


@njit(cache=True)
def advance(x, k, surf, p, c, acc, n_steps, out, out_every, out_row):
    """Advance the state by ``n_steps`` fixed steps; return the next free row of ``out``.

    Every ``out_every`` global steps a row of outputs is written to ``out`` while rows remain.
    """
    n = p[P_N]
    psi = p[P_PSI]
    lam = p[P_LAM]
    beta = p[P_BETA]
    h = p[P_H]
    h2 = 0.5 * h
    hpsi = h * psi
    inv_dth = p[P_INV_DTHETA]
    dth = p[P_DTHETA]
    w0 = c[C_W0]
    om0 = c[C_OMEGA0]
    v_min = c[C_V_MIN]
    mask = surf.shape[0] - 1
    n_nodes = surf.shape[0]
    rows = out.shape[0]

    tau = x[X_TAU]
    u = x[X_U]
    v = x[X_V]
    phi = x[X_PHI]
    om = x[X_OMEGA]
    ptd = x[X_PHI_TD]
    s_behind = x[X_S_BEHIND]
    hole = x[X_HOLE]
    since_stick = x[X_SINCE_STICK]
    k_last = k[K_LAST]
    regime = k[K_REGIME]
    steps = k[K_STEPS]
    w = x[X_W]
    t = x[X_T]
    delta = x[X_DELTA]
    g = x[X_G]

    a_time = acc[A_TIME]
    a_om = acc[A_OMEGA]
    a_om_min = acc[A_OMEGA_MIN]
    a_om_max = acc[A_OMEGA_MAX]
    a_w = acc[A_W]
    a_t = acc[A_T]
    a_ts = acc[A_TS]
    a_v = acc[A_V]
    a_stick = acc[A_STICK_TIME]
    a_bounce = acc[A_BOUNCE_TIME]
    a_wtd = acc[A_WORK_TOP_DRIVE]
    a_ww = acc[A_WORK_WEIGHT]
    a_wh = acc[A_WORK_HOIST]
    a_drot = acc[A_DISSIPATED_ROT]
    a_dax = acc[A_DISSIPATED_AX]

    for _ in range(n_steps):
        # 1. half drift
        u_m = u + h2 * v
        phi_m = phi + h2 * om
        ptd_m = ptd + h2 * om0
        ts = ptd_m - phi_m

        # 2. depth of cut on the surface left by earlier passes
        delta = u_m - _surface_at(surf, mask, phi_m, inv_dth, k_last, s_behind)

        # 3. set-valued laws, solved for the end-of-step velocities
        if delta < 0.0:
            regime = REGIME_OFF_BOTTOM
            w = 0.0
            t = 0.0
            g = 0.0
            v_new = v + hpsi * w0
            om_new = om + h * ts
        else:
            nd = n * delta
            stuck = False
            if regime == REGIME_STUCK:
                # stays stuck while T_s <= T_max; full friction only while pressed on the rock
                if v + hpsi * w0 >= 0.0:
                    t_max = nd + beta * lam
                else:
                    t_max = nd
                stuck = ts <= t_max
            if not stuck:
                v1 = v + hpsi * (w0 - nd - lam)          # branch g = 1 (v+ > 0)
                if v1 > 0.0:
                    g = 1.0
                    v_new = v1
                else:
                    v0 = v + hpsi * (w0 - nd)           # branch g = 0 (v+ < 0)
                    if v0 < 0.0:
                        g = 0.0
                        v_new = v0
                    else:                               # axial stick, g in [0, 1]
                        g = v0 / (hpsi * lam) if lam > 0.0 else 0.0
                        v_new = 0.0
                w = nd + lam * g
                t = nd + beta * lam * g
                om_free = om + h * (ts - t)
                if om_free > 0.0:
                    regime = REGIME_ROTATING
                    om_new = om_free
                else:
                    stuck = True
            if stuck:
                # omega+ = 0, torque is the reaction; the rock only pushes (v+ <= 0)
                regime = REGIME_STUCK
                om_new = 0.0
                t = ts + om / h
                g = 1.0
                v_try = v + hpsi * w0
                if v_try > 0.0:
                    v_new = 0.0
                    w = w0 + v / hpsi
                else:
                    v_new = v_try
                    w = 0.0
                    g = 0.0

        # hoisting-speed limit: the drawworks holds the string back
        f_hoist = 0.0
        if v_new < v_min:
            f_hoist = (v_min - v_new) / hpsi
            v_new = v_min

        # 4. second half drift and the sweep of the blades over the rock
        v_bar = 0.5 * (v + v_new)
        om_bar = 0.5 * (om + om_new)
        u_new = u_m + h2 * v_new
        phi_new = phi_m + h2 * om_new
        k_new = np.int64(math.floor(phi_new * inv_dth))
        if k_new > k_last:
            k_first = k_last + 1
            if k_new - k_first >= n_nodes:
                k_first = k_new - n_nodes + 1
            dphi = phi_new - phi
            for kk in range(k_first, k_new + 1):
                frac = (kk * dth - phi) / dphi
                uc = u + frac * (u_new - u)
                j = kk & mask
                old = surf[j]
                if uc > old:
                    surf[j] = uc
                    if uc > hole:
                        hole = uc
                s_behind = old
            k_last = k_new
        elif k_new < k_last:
            # backward rotation, possible only off bottom: nothing is cut
            k_last = k_new
            s_behind = surf[k_new & mask]

        # accumulate the window integrals (forces act over the whole step)
        a_time += h
        a_om += h * om_bar
        a_w += h * w
        a_t += h * t
        a_ts += h * ts
        a_v += h * v_bar
        if regime == REGIME_STUCK:
            a_stick += h
        elif regime == REGIME_OFF_BOTTOM:
            a_bounce += h
        a_wtd += h * ts * om0
        a_ww += h * w0 * v_bar
        a_wh += h * f_hoist * v_bar
        a_drot += h * t * om_bar
        a_dax += h * w * v_bar

        u = u_new
        v = v_new
        phi = phi_new
        om = om_new
        ptd = ptd_m + h2 * om0
        tau += h
        steps += 1
        if om < a_om_min:
            a_om_min = om
        if om > a_om_max:
            a_om_max = om
        if regime == REGIME_STUCK:
            since_stick = 0.0
        else:
            since_stick += h

        if out_row < rows and steps % out_every == 0:
            out[out_row, O_TAU] = tau
            out[out_row, O_U] = u
            out[out_row, O_V] = v
            out[out_row, O_PHI] = phi
            out[out_row, O_OMEGA] = om
            out[out_row, O_PHI_TD] = ptd
            out[out_row, O_W] = w
            out[out_row, O_T] = t
            out[out_row, O_TS] = ptd - phi
            out[out_row, O_DELTA] = delta
            out[out_row, O_REGIME] = regime
            out[out_row, O_W0] = w0
            out[out_row, O_OMEGA0] = om0
            out[out_row, O_G] = g
            out_row += 1

    x[X_TAU] = tau
    x[X_U] = u
    x[X_V] = v
    x[X_PHI] = phi
    x[X_OMEGA] = om
    x[X_PHI_TD] = ptd
    x[X_S_BEHIND] = s_behind
    x[X_HOLE] = hole
    x[X_SINCE_STICK] = since_stick
    x[X_W] = w
    x[X_T] = t
    x[X_TS] = ptd - phi
    x[X_DELTA] = delta
    x[X_G] = g
    k[K_LAST] = k_last
    k[K_REGIME] = regime
    k[K_STEPS] = steps
    acc[A_TIME] = a_time
    acc[A_OMEGA] = a_om
    acc[A_OMEGA_MIN] = a_om_min
    acc[A_OMEGA_MAX] = a_om_max
    acc[A_W] = a_w
    acc[A_T] = a_t
    acc[A_TS] = a_ts
    acc[A_V] = a_v
    acc[A_STICK_TIME] = a_stick
    acc[A_BOUNCE_TIME] = a_bounce
    acc[A_WORK_TOP_DRIVE] = a_wtd
    acc[A_WORK_WEIGHT] = a_ww
    acc[A_WORK_HOIST] = a_wh
    acc[A_DISSIPATED_ROT] = a_drot
    acc[A_DISSIPATED_AX] = a_dax
    acc[A_W0] += n_steps * h * w0
    acc[A_OMEGA0] += n_steps * h * om0
    return out_row
