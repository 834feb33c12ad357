"""The numba stepping kernel: fixed step, exact set-valued bit-rock laws, fixed memory.

Scheme (a Moreau midpoint time-stepping scheme, second order in smooth phases and through the
switches of the laws that it locates):

1. drift half a step: u_m = u + h/2 v, phi_m = phi + h/2 omega, phi_td_m = phi_td + h/2 omega_td
   (the top drive's speed: omega0 in kinematic mode); with a top drive in the loop
   (``_drive_step``), its end-of-step speed under the motor torque against the string
   torque phi_td_m - phi_m, the PI's P term implicit, its limits clamping the motor torque;
2. evaluate the depth of cut delta = u_m - S(phi_m) on the rock surface left by earlier passes
   (``bit_rock._surface_at``);
3. solve the set-valued laws of the model contract (section 2.2, msg_docs/model.md) *implicitly*
   for the end-of-step velocities (``bit_rock._bit_rock_law``, shared with the distributed
   kernel): the wear-flat factor g from the sign of v+ (``_contact_law``), stick from the sign
   of omega+ and the breakaway torque (``_breakaway_torque``), the rock reaction from the sign
   of v+ while stuck (``_stick_reaction``); each is a one-dimensional complementarity problem
   solved exactly by trying its branches, so no law is ever regularised; then the drawworks'
   hoisting-speed limit (``_hoist_limit``). If a law switches inside the step (the bit stops
   turning, breaks away, its wear flats lift off or land, it leaves the rock or lands),
   ``_bit_rock_law`` says where, and the step is taken in parts split there
   (``_located_step``);
4. drift the second half with the new velocities and let the blades sweep the surface:
   S(theta) <- max(S(theta), u) at every grid node passed (``bit_rock._sweep``, shared too);
   add the step to the window integrals (``_accumulate``).

The top drive's limits (saturation, rate limit) are clamps of its motor torque, not laws of the
bit: a clamp that engages inside a step is not located. In kinematic mode (the default) the
drive's branch is skipped and the arithmetic is the seed's, bit for bit.

The surface is an array of N = 2^m nodes over one sector 2*pi/n, linear between nodes. All state
lives in preallocated arrays indexed by the constants of ``state_layout`` (the one declaration
of the state), so advancing allocates nothing. The stepping functions are compiled without
numba's runtime (they allocate nothing), so a helper that takes an array costs no reference
counting in the loop: the sweep (``bit_rock._sweep``), the drift and the drive's step
(``_drift_and_drive``, ``_drive_advance``) and the output rows (``_write_row``) are the
distributed kernel's too. Within a call the state lives in locals: ``_load``/``_store`` (and
``_load_drive``/``_store_drive``) move it between the arrays and the loop, around the steps
split at a switch (``_located_step``, which steps the bit too) and at the call's ends, for both
kernels; a new slot that a step changes joins them, one read once a call is read there.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import bit_rock, state_layout
from .bit_rock import REGIME_OFF_BOTTOM as REGIME_OFF_BOTTOM  # the regimes, read here as kn.*
from .bit_rock import REGIME_ROTATING as REGIME_ROTATING
from .bit_rock import REGIME_STUCK as REGIME_STUCK
from .bit_rock import (  # the bit on the rock, shared
    _bit_rock_law,
    _surface_at,
    _sweep,
)
from .numba_cache import follow
from .state_layout import (  # the layout of the state arrays, one declaration
    A_BOUNCE_TIME,
    A_DISSIPATED_AX,
    A_DISSIPATED_ROT,
    A_OMEGA,
    A_OMEGA0,
    A_OMEGA_MAX,
    A_OMEGA_MIN,
    A_OMEGA_TD,
    A_STICK_TIME,
    A_T,
    A_TIME,
    A_TM,
    A_TS,
    A_V,
    A_W,
    A_W0,
    A_WORK_HOIST,
    A_WORK_MOTOR,
    A_WORK_TOP_DRIVE,
    A_WORK_WEIGHT,
    C_OMEGA0,
    C_T_CMD,
    C_V_MIN,
    C_W0,
    K_LAST,
    K_REFUSED,
    K_REGIME,
    K_SAMPLED,
    K_STEPS,
    O_DELTA,
    O_G,
    O_OMEGA,
    O_OMEGA0,
    O_OMEGA_TD,
    O_PHI,
    O_PHI_TD,
    O_REGIME,
    O_T,
    O_TAU,
    O_TM,
    O_TS,
    O_U,
    O_V,
    O_W,
    O_W0,
    P_BETA,
    P_DTHETA,
    P_H,
    P_INV_DTHETA,
    P_J,
    P_KI,
    P_KP,
    P_LAG,
    P_LAG_END,
    P_LAG_MEAN,
    P_LAM,
    P_MODE,
    P_N,
    P_PSI,
    P_RATE,
    P_T_MAX,
    P_T_MIN,
    X_DELTA,
    X_DRIVE_I,
    X_G,
    X_HOLE,
    X_OMEGA,
    X_OMEGA_TD,
    X_PHI,
    X_PHI_TD,
    X_S_BEHIND,
    X_SINCE_STICK,
    X_SUM_T,
    X_SUM_W,
    X_T,
    X_TAU,
    X_TM,
    X_TREF,
    X_TS,
    X_U,
    X_V,
    X_W,
)

follow(__file__, bit_rock.__file__, state_layout.__file__)   # the cache follows what it compiles

MODE_KINEMATIC, MODE_SPEED, MODE_TORQUE = 0, 1, 2   # the top drive's (top_drive.MODES)

EVENT_MARGIN = 1e-9     # a switch closer than this (fraction of the step) to its ends is not split
MAX_SPLITS = 2          # switches located per step


@njit(cache=True, inline="always")
def _drive_step(mode, om_td, integral, tm, ref, ts, om_set, t_cmd, step, hj, kp, t_lo, t_hi,
               c_end, c_mean):
    """One step h of the top drive; returns (Omega_TD+, T_m+, reference+, mean T_m).

    The reference (``t_cmd`` in torque mode; in speed mode the PI kp (om_set - mean Omega_TD)
    + ``integral``, its integral term at the step's midpoint) is limited to ``step`` (the rate
    limit times h) from the last reference ``ref`` and to [t_lo, t_hi]; the motor torque T_m
    follows it through the lag (weights ``c_end``, ``c_mean`` of ``DriveGroups.lag_weights``);
    the top drive (``hj`` = h/j) turns under the mean T_m against the string's torque ``ts`` at
    the midpoint. The P term is implicit in Omega_TD+ (a linear equation; with the limits a
    monotone one, so the clamped branch is the solution when the unclamped one is out of
    bounds)."""
    lo = min(max(ref - step, t_lo), t_hi)
    hi = min(max(ref + step, t_lo), t_hi)
    other = (1.0 - c_mean) * tm - ts
    if mode == MODE_TORQUE:
        r = min(max(t_cmd, lo), hi)
        om_new = om_td + hj * (c_mean * r + other)
    else:
        half = 0.5 * kp
        a = kp * om_set - half * om_td + integral
        om_new = (om_td + hj * (c_mean * a + other)) / (1.0 + hj * c_mean * half)
        r = a - half * om_new
        if r > hi or r < lo:
            r = min(max(r, lo), hi)
            om_new = om_td + hj * (c_mean * r + other)
    return om_new, tm + c_end * (r - tm), r, tm + c_mean * (r - tm)


@njit(cache=True, inline="always")
def _drive_advance(mode, om_td, integral, tm, ref, ts, om_set, t_cmd, h2, ki, step, hj, kp,
                   t_lo, t_hi, c_end, c_mean):
    """The top drive over one step from its state (``h2`` half the step): the speed PI's
    integral term at the midpoint (speed mode), then ``_drive_step``; returns (the integral
    term at the midpoint, Omega_TD+, T_m+, reference+, mean T_m). The lumped and the
    distributed kernel both step their drive here."""
    integral_m = integral
    if mode == MODE_SPEED:
        integral_m = integral + h2 * ki * (om_set - om_td)
    om_new, tm_new, ref_new, t_bar = _drive_step(mode, om_td, integral_m, tm, ref, ts, om_set,
                                                 t_cmd, step, hj, kp, t_lo, t_hi, c_end, c_mean)
    return integral_m, om_new, tm_new, ref_new, t_bar


@njit(cache=True, inline="always")
def _integral_end(mode, integral, integral_m, h2, ki, om_set, om_new, t_lo, t_hi):
    """The speed PI's integral term at the step's end, held within the torque limits (other
    modes: ``integral`` unchanged)."""
    if mode == MODE_SPEED:
        return min(max(integral_m + h2 * ki * (om_set - om_new), t_lo), t_hi)
    return integral


@njit(cache=True, inline="always")
def _drive_books(hs, ts, t_bar, om_td_bar, a_tm, a_wm, a_wtd):
    """The drive's window integrals over a step (or part) ``hs``: the motor torque, the
    motor's work and the string's top torque's work; returns them updated."""
    return a_tm + hs * t_bar, a_wm + hs * t_bar * om_td_bar, a_wtd + hs * ts * om_td_bar


@njit(cache=True, inline="always")
def _drift_and_drive(drive, mode, u, v, phi, om, ptd, om_td, integral, tm, ref, h2, om0, t_cmd,
                     ki, step, hj, kp, t_min, t_max, c_end, c_mean):
    """The first half of a step (or part; ``h2`` its half): the bit and the top drive drift
    half a step, the string's torque at the midpoint, and with the drive in the loop
    (``drive``) its step (``_drive_advance``); returns (u_m, phi_m, phi_TD_m, string torque,
    the PI's integral term at the midpoint, Omega_TD+, T_m+, reference+, mean T_m, mean
    Omega_TD). The kinematic drive keeps its speed and holds its state."""
    u_m = u + h2 * v
    phi_m = phi + h2 * om
    ptd_m = ptd + h2 * om_td
    ts = ptd_m - phi_m
    om_td_new = om_td
    om_td_bar = om_td
    integral_m, tm_new, ref_new, t_bar = integral, tm, ref, tm
    if drive:
        integral_m, om_td_new, tm_new, ref_new, t_bar = _drive_advance(
            mode, om_td, integral, tm, ref, ts, om0, t_cmd, h2, ki, step, hj, kp, t_min, t_max,
            c_end, c_mean)
        om_td_bar = 0.5 * (om_td + om_td_new)
    return u_m, phi_m, ptd_m, ts, integral_m, om_td_new, tm_new, ref_new, t_bar, om_td_bar


@njit(cache=True, inline="always")
def _write_row(o, tau, u, v, phi, om, ptd, sum_w, sum_t, n, ts, delta, regime, w0, om0, g,
               om_td, tm):
    """One output row ``o`` (the columns O_*): the state now, the forces' means over the
    row's ``n`` steps (their sums ``sum_w``, ``sum_t``). Both kernels write their rows here."""
    o[O_TAU] = tau
    o[O_U] = u
    o[O_V] = v
    o[O_PHI] = phi
    o[O_OMEGA] = om
    o[O_PHI_TD] = ptd
    o[O_W] = sum_w / n
    o[O_T] = sum_t / n
    o[O_TS] = ts
    o[O_DELTA] = delta
    o[O_REGIME] = regime
    o[O_W0] = w0
    o[O_OMEGA0] = om0
    o[O_G] = g
    o[O_OMEGA_TD] = om_td
    o[O_TM] = tm


@njit(cache=True, inline="always")
def _fold_sample(h, a_w, a_t, sum_w, sum_t):
    """A sample taken (a row written): its force sums folded into the window's integrals of
    w and t, and the next sample's sums started; returns (a_w, a_t, 0, 0)."""
    return a_w + h * sum_w, a_t + h * sum_t, 0.0, 0.0


@njit(cache=True, inline="always")
def _hoist_limit(v_new, v_min, hpsi):
    """The drawworks holds the string back: v+ >= v_min; returns (v+, hoist force)."""
    if v_new < v_min:
        return v_min, (v_min - v_new) / hpsi
    return v_new, 0.0


@njit(cache=True, inline="always")
def _accumulate(a, h, regime, om_bar, v_bar, w, t, ts, f_hoist):
    """The window integrals (forces act over the whole step); ``a`` is the tuple (omega, ts,
    v, stick, bounce, work hoist, dissipated rotation, dissipated axial) and the updated tuple
    is returned. The integrals of w and t are kept as the sample sums (X_SUM_W, X_SUM_T),
    folded in at each sample; time and the work of the held commands (omega0 ts, w0 v) are
    added once a call, in ``advance``."""
    a_om, a_ts, a_v, a_stick, a_bounce, a_wh, a_drot, a_dax = a
    if regime == REGIME_STUCK:
        a_stick += h
    elif regime == REGIME_OFF_BOTTOM:
        a_bounce += h
    return (a_om + h * om_bar, a_ts + h * ts, a_v + h * v_bar, a_stick, a_bounce,
            a_wh + h * f_hoist * v_bar, a_drot + h * t * om_bar, a_dax + h * w * v_bar)


@njit(cache=True, inline="always")
def _load(x, k, acc):
    """The state arrays as the stepper's locals."""
    return (x[X_TAU], x[X_U], x[X_V], x[X_PHI], x[X_OMEGA], x[X_PHI_TD], x[X_S_BEHIND],
            x[X_HOLE], x[X_SINCE_STICK], x[X_W], x[X_T], x[X_DELTA], x[X_G], x[X_SUM_W],
            x[X_SUM_T], k[K_LAST], k[K_REGIME], acc[A_OMEGA_MIN], acc[A_OMEGA_MAX],
            (acc[A_OMEGA], acc[A_TS], acc[A_V], acc[A_STICK_TIME],
             acc[A_BOUNCE_TIME], acc[A_WORK_HOIST],
             acc[A_DISSIPATED_ROT], acc[A_DISSIPATED_AX]))


@njit(cache=True, inline="always")
def _store(x, k, acc, tau, u, v, phi, om, ptd, s_behind, hole, since_stick, w, t, delta, g,
           sum_w, sum_t, k_last, regime, a_om_min, a_om_max, a):
    """The stepper's locals back into the state arrays (inverse of ``_load``)."""
    x[X_TAU], x[X_U], x[X_V], x[X_PHI], x[X_OMEGA], x[X_PHI_TD] = tau, u, v, phi, om, ptd
    x[X_S_BEHIND], x[X_HOLE], x[X_SINCE_STICK] = s_behind, hole, since_stick
    x[X_W], x[X_T], x[X_TS], x[X_DELTA], x[X_G] = w, t, ptd - phi, delta, g
    x[X_SUM_W], x[X_SUM_T] = sum_w, sum_t
    k[K_LAST], k[K_REGIME] = k_last, regime
    acc[A_OMEGA_MIN], acc[A_OMEGA_MAX] = a_om_min, a_om_max
    (acc[A_OMEGA], acc[A_TS], acc[A_V], acc[A_STICK_TIME], acc[A_BOUNCE_TIME],
     acc[A_WORK_HOIST], acc[A_DISSIPATED_ROT],
     acc[A_DISSIPATED_AX]) = a


@njit(cache=True, inline="always")
def _load_drive(x, acc):
    """The top drive's state and window integrals as the stepper's locals."""
    return (x[X_OMEGA_TD], x[X_DRIVE_I], x[X_TM], x[X_TREF], acc[A_OMEGA_TD], acc[A_TM],
            acc[A_WORK_MOTOR], acc[A_WORK_TOP_DRIVE])


@njit(cache=True, inline="always")
def _store_drive(x, acc, om_td, integral, tm, ref, a_otd, a_tm, a_wm, a_wtd):
    """The top drive's locals back into the state arrays (inverse of ``_load_drive``)."""
    x[X_OMEGA_TD], x[X_DRIVE_I], x[X_TM], x[X_TREF] = om_td, integral, tm, ref
    acc[A_OMEGA_TD], acc[A_TM], acc[A_WORK_MOTOR], acc[A_WORK_TOP_DRIVE] = a_otd, a_tm, a_wm, a_wtd


@njit(cache=True, _nrt=False)
def _located_step(x, k, surf, p, c, acc, event):
    """One step taken in parts split where a law switches, from the state arrays and back.

    ``event`` is where the first switch falls, as a fraction of the step (``_bit_rock_law``):
    the step is taken up to it, then on from it, each part with the same midpoint scheme, so
    the laws stay linear within each part and the scheme keeps its second order through the
    switch; a further switch inside a part is located too, up to MAX_SPLITS in all. Only the
    steps holding a switch come here (a few per stick-slip cycle), so ``advance`` keeps its
    plain loop for the others. A part that would turn the bit over a sector sets K_REFUSED and
    stops, the parts before it taken.
    """
    n, lam, beta, h, psi = p[P_N], p[P_LAM], p[P_BETA], p[P_H], p[P_PSI]
    inv_dth, dth = p[P_INV_DTHETA], p[P_DTHETA]
    w0, om0, v_min, t_cmd = c[C_W0], c[C_OMEGA0], c[C_V_MIN], c[C_T_CMD]
    mode = np.int64(p[P_MODE])
    drive = mode != MODE_KINEMATIC
    j_td, t_max, t_min, rate, lag, kp, ki = (p[P_J], p[P_T_MAX], p[P_T_MIN], p[P_RATE],
                                             p[P_LAG], p[P_KP], p[P_KI])
    n_nodes = surf.shape[0]
    mask = n_nodes - 1
    sector = n_nodes * dth
    (tau, u, v, phi, om, ptd, s_behind, hole, since_stick, w, t, delta, g, sum_w, sum_t, k_last,
     regime, a_om_min, a_om_max, a) = _load(x, k, acc)
    om_td, integral, tm, ref, a_otd, a_tm, a_wm, a_wtd = _load_drive(x, acc)
    hs = event * h
    left = h
    splits = 1
    while True:
        h2 = 0.5 * hs
        hpsi = hs * psi
        c_end, c_mean = 1.0, 1.0
        if drive and lag > 0.0:             # the lag's weights over this part
            c_end = -math.expm1(-hs / lag)
            c_mean = 1.0 - c_end * lag / hs
        (u_m, phi_m, ptd_m, ts, integral_m, om_td_new, tm_new, ref_new, t_bar,
         om_td_bar) = _drift_and_drive(drive, mode, u, v, phi, om, ptd, om_td, integral, tm, ref,
                                       h2, om0, t_cmd, ki, rate * hs, hs / j_td, kp, t_min, t_max,
                                       c_end, c_mean)
        s_m, slope = _surface_at(surf, mask, phi_m, inv_dth, k_last, s_behind)
        delta_new = u_m - s_m
        regime_new, w_new, t_new, g_new, v_new, om_new, event = _bit_rock_law(
            delta_new, slope, regime, v, om, ts, w0, om_td_bar, n, lam, beta, hs, hpsi)
        if splits < MAX_SPLITS and EVENT_MARGIN < event < 1.0 - EVENT_MARGIN:
            splits += 1
            hs *= event
            continue
        v_new, f_hoist = _hoist_limit(v_new, v_min, hpsi)
        phi_new = phi_m + h2 * om_new
        if phi_new - phi > sector:
            k[K_REFUSED] = 1
            break
        regime, w, t, g, delta = regime_new, w_new, t_new, g_new, delta_new
        u_new = u_m + h2 * v_new
        k_last, s_behind, hole = _sweep(surf, mask, n_nodes, dth, inv_dth, k_last, s_behind, hole,
                                        phi, phi_new, u, u_new)
        a = _accumulate(a, hs, regime, 0.5 * (om + om_new), 0.5 * (v + v_new), w, t, ts,
                        f_hoist)
        sum_w += w * (hs / h)
        sum_t += t * (hs / h)
        u, v, phi, om, ptd = u_new, v_new, phi_new, om_new, ptd_m + h2 * om_td_new
        if drive:               # (A_OMEGA_TD: _steps books the top drive's turn)
            a_tm, a_wm, a_wtd = _drive_books(hs, ts, t_bar, om_td_bar, a_tm, a_wm, a_wtd)
            integral = _integral_end(mode, integral, integral_m, h2, ki, om0, om_td_new, t_min,
                                     t_max)
            om_td, tm, ref = om_td_new, tm_new, ref_new
        tau += hs
        if om < a_om_min:
            a_om_min = om
        if om > a_om_max:
            a_om_max = om
        since_stick = 0.0 if regime == REGIME_STUCK else since_stick + hs
        left -= hs
        if left <= 0.0:
            break
        hs = left
    _store(x, k, acc, tau, u, v, phi, om, ptd, s_behind, hole, since_stick, w, t, delta, g,
           sum_w, sum_t, k_last, regime, a_om_min, a_om_max, a)
    _store_drive(x, acc, om_td, integral, tm, ref, a_otd, a_tm, a_wm, a_wtd)


def advance(x, k, surf, p, c, acc, n_steps, out, out_every, out_row):
    """Advance the state by ``n_steps`` fixed steps; return the next free row of ``out``.

    Every ``out_every`` global steps a row of outputs is written to ``out`` while rows remain.
    A step in which a law switches is taken in parts by ``_located_step``. A step that would
    turn the bit forward by more than a sector 2 pi/n is refused: the rock surface cannot be
    swept (every node would be passed more than once) nor the depth of cut measured; the call
    stops before it, state as after the previous step, K_REFUSED = 1.

    Two entry points share the loop ``_steps``, each compiled when first used and each calling
    it with ``drive`` a constant (its one call site there, so the compiler inlines it and drops
    the dead branch): ``advance_kinematic``, the seed's loop at the seed's speed, and
    ``advance_drive``. This picks the one for the top drive's mode (a caller stepping often
    keeps ``stepper(mode)`` instead).
    """
    return stepper(int(p[P_MODE]))(x, k, surf, p, c, acc, n_steps, out, out_every, out_row)


def stepper(mode: int):
    """The compiled ``advance`` for the top drive's mode (MODE_*)."""
    return advance_kinematic if mode == MODE_KINEMATIC else advance_drive


@njit(cache=True, _nrt=False)
def advance_kinematic(x, k, surf, p, c, acc, n_steps, out, out_every, out_row):
    """``advance`` with the ideal speed source; its drive integrals are booked around the loop
    (its motor torque is the string's)."""
    om0 = c[C_OMEGA0]
    x[X_OMEGA_TD] = om0
    ts0_sum, steps0 = acc[A_TS], k[K_STEPS]
    out_row = _steps(x, k, surf, p, c, acc, n_steps, out, out_every, out_row, False)
    acc[A_WORK_MOTOR] += om0 * (acc[A_TS] - ts0_sum)
    acc[A_TM] += acc[A_TS] - ts0_sum
    acc[A_OMEGA_TD] += (k[K_STEPS] - steps0) * p[P_H] * om0
    return out_row


@njit(cache=True, _nrt=False)
def advance_drive(x, k, surf, p, c, acc, n_steps, out, out_every, out_row):
    """``advance`` with the top drive in the loop (speed or torque mode)."""
    return _steps(x, k, surf, p, c, acc, n_steps, out, out_every, out_row, True)


@njit(cache=True, _nrt=False)
def _steps(x, k, surf, p, c, acc, n_steps, out, out_every, out_row, drive):
    """``advance``'s loop; ``drive`` (a constant at each call): the top drive is in the loop
    (speed or torque mode), not the ideal speed source."""
    n = p[P_N]
    lam = p[P_LAM]
    beta = p[P_BETA]
    h = p[P_H]
    h2 = 0.5 * h
    hpsi = h * p[P_PSI]
    inv_dth = p[P_INV_DTHETA]
    dth = p[P_DTHETA]
    w0 = c[C_W0]
    om0 = c[C_OMEGA0]
    v_min = c[C_V_MIN]
    t_cmd = c[C_T_CMD]
    mode = np.int64(p[P_MODE])
    j_td, t_max, t_min, rate, kp, ki = (p[P_J], p[P_T_MAX], p[P_T_MIN], p[P_RATE], p[P_KP],
                                        p[P_KI])
    c_end, c_mean = p[P_LAG_END], p[P_LAG_MEAN]
    rate_step = rate * h
    hj = h / j_td
    n_nodes = surf.shape[0]
    mask = n_nodes - 1
    rows = out.shape[0]
    sector = n_nodes * dth
    k[K_REFUSED] = 0

    (tau, u, v, phi, om, ptd, s_behind, hole, since_stick, w, t, delta, g, sum_w, sum_t, k_last,
     regime, a_om_min, a_om_max, a) = _load(x, k, acc)
    if drive:
        om_td, integral, tm, ref, a_otd, a_tm, a_wm, a_wtd = _load_drive(x, acc)
    else:                   # the ideal speed source (``advance`` books its drive integrals)
        om_td = om0
        integral = tm = ref = a_otd = a_tm = a_wm = a_wtd = 0.0
    ptd0 = ptd
    steps, sampled = k[K_STEPS], k[K_SAMPLED]
    steps0 = steps
    ts0_sum, v0_sum = acc[A_TS], acc[A_V]
    a_w, a_t = acc[A_W], acc[A_T]

    for _ in range(n_steps):
        # 1. half drift, the top drive under its motor torque against the string's
        (u_m, phi_m, ptd_m, ts, integral_m, om_td_new, tm_new, ref_new, t_bar,
         om_td_bar) = _drift_and_drive(drive, mode, u, v, phi, om, ptd, om_td, integral, tm, ref,
                                       h2, om0, t_cmd, ki, rate_step, hj, kp, t_min, t_max,
                                       c_end, c_mean)
        # 2. depth of cut on the surface left by earlier passes
        s_m, slope = _surface_at(surf, mask, phi_m, inv_dth, k_last, s_behind)
        delta_new = u_m - s_m
        # 3. set-valued laws, solved for the end-of-step velocities
        regime_new, w_new, t_new, g_new, v_new, om_new, event = _bit_rock_law(
            delta_new, slope, regime, v, om, ts, w0, om_td_bar, n, lam, beta, h, hpsi)
        if EVENT_MARGIN < event < 1.0 - EVENT_MARGIN:
            # a law switches inside the step: take it in parts (rare)
            _store(x, k, acc, tau, u, v, phi, om, ptd, s_behind, hole, since_stick, w, t, delta,
                   g, sum_w, sum_t, k_last, regime, a_om_min, a_om_max, a)
            if drive:   # (kinematic mode: the parts leave the drive's state as it is)
                _store_drive(x, acc, om_td, integral, tm, ref, a_otd, a_tm, a_wm, a_wtd)
            _located_step(x, k, surf, p, c, acc, event)
            (tau, u, v, phi, om, ptd, s_behind, hole, since_stick, w, t, delta, g, sum_w, sum_t,
             k_last, regime, a_om_min, a_om_max, a) = _load(x, k, acc)
            if drive:
                om_td, integral, tm, ref, a_otd, a_tm, a_wm, a_wtd = _load_drive(x, acc)
            if k[K_REFUSED]:
                break
        else:
            v_new, f_hoist = _hoist_limit(v_new, v_min, hpsi)
            # 4. second half drift and the sweep of the blades over the rock
            phi_new = phi_m + h2 * om_new
            if phi_new - phi > sector:
                k[K_REFUSED] = 1                    # more than a sector in one step: refused
                break
            regime, w, t, g, delta = regime_new, w_new, t_new, g_new, delta_new
            v_bar = 0.5 * (v + v_new)
            om_bar = 0.5 * (om + om_new)
            u_new = u_m + h2 * v_new
            k_last, s_behind, hole = _sweep(surf, mask, n_nodes, dth, inv_dth, k_last,
                                            s_behind, hole, phi, phi_new, u, u_new)
            a = _accumulate(a, h, regime, om_bar, v_bar, w, t, ts, f_hoist)
            sum_w += w              # what a sensor sees: forces averaged over its sample
            sum_t += t              # (and, folded in at each sample, the window's integrals)

            u = u_new
            v = v_new
            phi = phi_new
            om = om_new
            ptd = ptd_m + h2 * om_td_new
            if drive:
                a_tm, a_wm, a_wtd = _drive_books(h, ts, t_bar, om_td_bar, a_tm, a_wm, a_wtd)
                integral = _integral_end(mode, integral, integral_m, h2, ki, om0, om_td_new,
                                         t_min, t_max)
                om_td = om_td_new
                tm = tm_new
                ref = ref_new
            tau += h
            if om < a_om_min:
                a_om_min = om
            if om > a_om_max:
                a_om_max = om
            if regime == REGIME_STUCK:
                since_stick = 0.0
            else:
                since_stick += h
        steps += 1
        if out_row < rows and steps % out_every == 0:
            _write_row(out[out_row], tau, u, v, phi, om, ptd, sum_w, sum_t, steps - sampled,
                       ptd - phi, delta, regime, w0, om0, g, om_td, tm if drive else ptd - phi)
            out_row += 1
            a_w, a_t, sum_w, sum_t = _fold_sample(h, a_w, a_t, sum_w, sum_t)
            sampled = steps

    _store(x, k, acc, tau, u, v, phi, om, ptd, s_behind, hole, since_stick, w, t, delta, g,
           sum_w, sum_t, k_last, regime, a_om_min, a_om_max, a)
    if drive:
        a_otd += ptd - ptd0     # the integral of omega_td: the top drive's turn, exactly
        _store_drive(x, acc, om_td, integral, tm, ref, a_otd, a_tm, a_wm, a_wtd)
    k[K_STEPS], k[K_SAMPLED] = steps, sampled
    acc[A_W], acc[A_T] = a_w, a_t
    # integrals of the commands times a state: the commands are held over the call
    acc[A_TIME] += (steps - steps0) * h
    if not drive:           # the ideal speed source: its torque is the string's
        acc[A_WORK_TOP_DRIVE] += om0 * (acc[A_TS] - ts0_sum)
    acc[A_WORK_WEIGHT] += w0 * (acc[A_V] - v0_sum)
    acc[A_W0] += (steps - steps0) * h * w0
    acc[A_OMEGA0] += (steps - steps0) * h * om0
    return out_row
