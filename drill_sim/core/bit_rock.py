"""The bit on the rock, shared by the lumped and the distributed kernels (which inline it):
the set-valued bit-rock laws of the model contract (section 2.2, msg_docs/model.md), solved
exactly for one step by trying their branches, never regularised; the rock surface the
previous blades left; and the blades' sweep over it. ``kernel`` describes the scheme.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

REGIME_ROTATING, REGIME_STUCK, REGIME_OFF_BOTTOM = 0, 1, 2


@njit(cache=True, inline="always")
def _surface_at(surf, mask, phi, inv_dtheta, k_last, s_behind):
    """The rock surface S(phi) before the current pass, linear between nodes, and its slope."""
    pos = phi * inv_dtheta
    km = math.floor(pos)
    frac = pos - km
    k0 = np.int64(km)
    if k0 == k_last:
        s0 = s_behind          # node k_last was already overwritten by this pass
    else:
        s0 = surf[k0 & mask]
    s1 = surf[(k0 + 1) & mask]
    return s0 + frac * (s1 - s0), (s1 - s0) * inv_dtheta


@njit(cache=True, inline="always")
def _breakaway_torque(v, hpsi, w0, nd, beta_lam):
    """The stick law: a stuck bit stays stuck while T_s <= T_max.

    T_max = n delta + beta lambda (cutting plus fully mobilised wear-flat friction) while the
    bit is pressed on the rock; n delta alone when it would lift off (friction lost).
    """
    if v + hpsi * w0 >= 0.0:
        return nd + beta_lam
    return nd


@njit(cache=True, inline="always")
def _contact_law(v, hpsi, w0, nd, lam):
    """Cutting plus wear-flat contact with the complementarity on g; returns (g, v+, and v+ of
    the branches g = 1 and g = 0).

    g = 1 if v+ > 0, g = 0 if v+ < 0, and g in [0, 1] keeping v+ = 0 (an axial stick): each
    branch is tried in turn on the implicit axial update v+ = v + h psi (w0 - n delta - lam g).
    """
    v1 = v + hpsi * (w0 - nd - lam)              # branch g = 1 (v+ > 0)
    if v1 > 0.0:
        return 1.0, v1, v1, v1 + hpsi * lam
    v0 = v + hpsi * (w0 - nd)                    # branch g = 0 (v+ < 0)
    if v0 < 0.0:
        return 0.0, v0, v1, v0
    friction = hpsi * lam                        # axial stick, g in [0, 1] (v0 <= friction)
    g = v0 / friction if friction > 0.0 else 0.0
    return g, 0.0, v1, v0


@njit(cache=True, inline="always")
def _stick_reaction(v, om, ts, w0, h, hpsi):
    """Omega+ = 0 held by the rock: the torque is the reaction; returns (v+, w, t, g).

    The rock only pushes: a bit moving down or resting stops (v+ = 0, w is the reaction);
    a bit that would rise keeps rising off the wear flats (the one-way axial hold).
    """
    t = ts + om / h
    v_try = v + hpsi * w0
    if v_try > 0.0:
        return 0.0, w0 + v / hpsi, t, 1.0
    return v_try, 0.0, t, 0.0


@njit(cache=True, inline="always")
def _crossing(earliest, start, end):
    """The earlier of ``earliest`` and where a switching function linear over the step crosses
    0 from ``start`` to ``end``, as fractions of the step (any value >= 1: no crossing)."""
    if start != end:
        at = start / (start - end)
        if at < earliest:
            return at
    return earliest


@njit(cache=True, inline="always")
def _bit_rock_law(delta, slope, regime, v, om, ts, w0, om_top, n, lam, beta, h, hpsi):
    """The set-valued bit-rock laws for one step; returns (regime, w, t, g, v+, omega+, event).

    Off bottom (delta < 0) nothing acts; in contact a stuck bit stays stuck while the stick law
    holds, otherwise the contact law gives g and v+, and a bit that would turn backwards is
    stuck instead (no backward rotation in contact). ``event`` locates the first switch of a
    law inside the step, as a fraction of it (>= 1: none): the bit stops turning (omega
    crosses 0), breaks away (T_s crosses T_max, T_s rising at the top drive's mean speed over
    the step ``om_top`` while stuck), its wear flats engage or lift off (V crosses 0), or it
    lands or leaves the rock (delta crosses 0, delta at the step's ends from its rate
    V - S' omega, S' the surface's ``slope``). The laws are linear between switches, so each
    crossing is interpolated linearly over the step.
    """
    event = 2.0
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
            t_max = _breakaway_torque(v, hpsi, w0, nd, beta * lam)
            stuck = ts <= t_max
            rise = h * om_top                    # T_s over the step, the bit held
            if ts + 0.5 * rise > t_max and rise > 0.0:
                event = _crossing(event, t_max - (ts - 0.5 * rise), t_max - (ts + 0.5 * rise))
        if not stuck:
            g, v_new, v1, v0 = _contact_law(v, hpsi, w0, nd, lam)
            if v > 0.0 and g < 1.0:              # the wear flats lift off
                event = _crossing(event, v, v1)
            elif v < 0.0 and g > 0.0:            # the wear flats land
                event = _crossing(event, v, v0)
            w = nd + lam * g
            t = nd + beta * lam * g
            om_new = om + h * (ts - t)
            if om_new > 0.0:
                regime = REGIME_ROTATING
            else:
                if regime == REGIME_ROTATING and om > 0.0:
                    event = _crossing(event, om, om_new)        # the bit stops turning
                stuck = True
        if stuck:
            regime = REGIME_STUCK
            om_new = 0.0
            v_new, w, t, g = _stick_reaction(v, om, ts, w0, h, hpsi)
    delta_start = delta - 0.5 * h * (v - slope * om)      # the bit lands or leaves the rock
    delta_end = delta + 0.5 * h * (v_new - slope * om_new)
    if (delta_start < 0.0) != (delta_end < 0.0):
        event = _crossing(event, delta_start, delta_end)
    return regime, w, t, g, v_new, om_new, event


@njit(cache=True, inline="always")
def _first_swept_node(k_last, k_new, n_nodes):
    """The blade sweep: the first node (absolute index) the blades pass in a step that ends
    past node ``k_new``; at most one sector's ``n_nodes`` nodes are swept in a step."""
    k_first = k_last + 1
    if k_new - k_first >= n_nodes:
        k_first = k_new - n_nodes + 1
    return k_first


@njit(cache=True, inline="always")
def _blade_height(theta, phi, dphi, u, u_new):
    """The blade sweep: the bit's axial position when a blade passes the angle ``theta`` in
    a step from (phi, u) to (phi + dphi, u_new), u linear in phi over the step."""
    frac = (theta - phi) / dphi
    return u + frac * (u_new - u)


@njit(cache=True, inline="always")
def _sweep(surf, mask, n_nodes, dth, inv_dth, k_last, s_behind, hole, phi, phi_new, u, u_new):
    """The blades sweep the rock in a step from (phi, u) to (phi_new, u_new): S <- max(S, u)
    at every node passed, backward rotation (possible only off bottom) cutting nothing;
    returns (k_last, s_behind, hole): the last node passed, its value before this pass and
    the deepest point of the surface."""
    k_new = np.int64(math.floor(phi_new * inv_dth))
    if k_new > k_last:
        dphi = phi_new - phi
        for kk in range(_first_swept_node(k_last, k_new, n_nodes), k_new + 1):
            uc = _blade_height(kk * dth, phi, dphi, u, u_new)
            j = kk & mask
            s_behind = surf[j]                 # the node's value before this pass
            if uc > s_behind:
                surf[j] = uc
                if uc > hole:
                    hole = uc
        k_last = k_new
    elif k_new < k_last:
        k_last = k_new
        s_behind = surf[k_new & mask]
    return k_last, s_behind, hole
