"""The numba stepper of the distributed string: the lumped kernel's bit, a string of delay lines.

Each step h: (1) read the Riemann invariants arriving at every junction this step: a segment
of travel time (N + f) h keeps the last N + 1 departures (slot ``steps mod (N + 1)``), and what
arrives is the mean over the step of what left its other end (N + f) h earlier, the departures
of N and N + 1 steps ago weighted 1 - f and f (exact for step means; the weighting dissipates
h f (1 - f) (x_N - x_N+1)^2 / (4 z), booked as the transport loss), then, in a segment of
damped material, through a first-order low-pass (time constant tau, the buffer's travel time
shortened by tau: a passage attenuated by 1/sqrt(1 + w^2 tau^2), delayed by D to second order
in w; passive, its dissipation booked with the dashpots'); (2) step the BHA
and the bit exactly as the lumped kernel does (the same inline laws ``_bit_rock_law``,
``_surface_at``, ``_first_swept_node``, ``_blade_height``, ``_accumulate``, switches located
and the step split there), with the string torque C (phi_td - phi) replaced by the pipe's
bottom torque a - (z + c) omega and W0 by its bottom force a_a - (z_a + c_a) v (omega, v
predicted at each part's midpoint from the last step's acceleration); (3) send the reflected
invariants b = a - 2 z omega_mean up from the BHA, solve the junctions (impedance change,
dashpot, and the relative dashpots across the parts between them that carry the material's
Kelvin-Voigt damping: one tridiagonal system) and the top boundary, and write the departing
invariants into the slots just read.

The top boundary: in kinematic mode the speed omega0 is imposed (departing a = b + 2 z omega0).
With a top drive in the loop (speed or torque mode) the top of the string is the drive's
inertia j: j dOmega_TD/dt = T_m - T_top with T_top = b + z Omega_TD, the characteristic
relation of the arriving invariant b (held over the step). The lumped kernel's ``_drive_step``
(PI, limits, rate limit, lag) solves it by the trapezoidal rule with the string torque taken at
the mean speed, b + z (Omega_TD + Omega_TD+)/2, which is the lumped call with h/j replaced by
(h/j)/(1 + h z/(2 j)) and the string torque by b + z Omega_TD. The departing invariant is
a = b + 2 z Omega_mean, so the drive's kinetic energy, the motor's work and the line's energy
balance exactly step by step (msg_docs/model.md, "The distributed string").
Memory is fixed: the ring buffers are sized at construction; nothing is allocated per step.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import bit_rock, state_layout
from . import kernel as kn
from .bit_rock import REGIME_STUCK, _bit_rock_law, _surface_at, _sweep
from .kernel import (
    EVENT_MARGIN,
    MAX_SPLITS,
    _accumulate,
    _drive_advance,
    _fold_sample,
    _integral_end,
    _load_drive,
    _store_drive,
    _write_row,
)
from .numba_cache import follow
from .state_layout import (  # the distributed string's slots, after the lumped ones
    A_DAMPED_AX,
    A_DAMPED_ROT,
    A_LOSS_AX,
    A_LOSS_ROT,
    A_WALL_AX,
    A_WALL_ROT,
    C_HOOK_POSITION,
    C_TOP_ABSORB,
    C_TOP_LEVEL,
    C_TOP_T_MAX,
    C_TOP_T_MIN,
    C_V_BLOCK,
    NOD,
    O_F_BOTTOM,
    O_F_TOP,
    O_T_BOTTOM,
    O_V_TOP,
    X_A_PREV,
    X_BHA_WALL_F,
    X_BHA_WALL_T,
    X_DOM,
    X_DV,
    X_F_BOTTOM,
    X_F_TOP,
    X_T_BOTTOM,
    X_V_TOP,
)

follow(__file__, kn.__file__, bit_rock.__file__, state_layout.__file__)   # what it compiles

WALL_SWEEPS = 200                        # Gauss-Seidel sweeps at most (converged: 1e-11)
NSCRATCH = 16                            # rows of ``advance``'s scratch (``_junctions_wall``)
# the scratch's rows: arriving a and b (torsional, axial), the stations' speeds (torsional,
# axial), the low-passes' next states (2 + 2), and the wall's contacts: forces, their speeds as
# the sweeps go, as solved (2 each: torque, axial force)
SC_TA, SC_TB, SC_AA, SC_AB, SC_WS, SC_WA = range(6)
SC_FORCE, SC_NOW, SC_SOLVED = 10, 12, 14


@njit(cache=True, inline="always")
def _arrivals(buf, off, n_seg, frac, z, slot_of, a_in, b_in, lowpass, state, new_state):
    """Invariants arriving this step: a at each segment's bottom, b at its top (``n_seg``: the
    slots per direction, N + 1; ``slot_of``: steps mod N + 1), each through the segment's
    material low-pass if it has one (time constant tau, trapezoidal: y+ = y + (h/tau)(x -
    (y + y+)/2), i.e. y+ = keep y + gain x with ``lowpass`` rows keep = (1 - r)/(1 + r) and
    gain = 2 r/(1 + r), r = h/(2 tau), gain 0: none; the step mean (y + y+)/2 arrives;
    ``state`` holds y, ``new_state`` gets y+, kept only if the step is: ``_keep``); returns
    the transport loss's rate and the low-passes' dissipation rate (times h: their energies;
    a low-pass stores tau y^2/(4 z) and dissipates (x - mean)^2/(4 z), exactly, step by
    step)."""
    loss = 0.0
    damped = 0.0
    for j in range(n_seg.size):
        m, f = n_seg[j], frac[j]
        old = slot_of[j]
        new = old + 1 if old + 1 < m else 0
        a0, a1 = buf[off[j] + old], buf[off[j] + new]
        b0, b1 = buf[off[j] + m + old], buf[off[j] + m + new]
        a_x = a1 + f * (a0 - a1)
        b_x = b1 + f * (b0 - b1)
        loss += f * (1.0 - f) * ((a1 - a0) ** 2 + (b1 - b0) ** 2) / (4.0 * z[j])
        gain = lowpass[1, j]
        if gain > 0.0:
            keep = lowpass[0, j]
            ya, yb = state[0, j], state[1, j]
            ya_new = keep * ya + gain * a_x
            yb_new = keep * yb + gain * b_x
            new_state[0, j], new_state[1, j] = ya_new, yb_new
            a_m, b_m = 0.5 * (ya + ya_new), 0.5 * (yb + yb_new)
            damped += ((a_x - a_m) ** 2 + (b_x - b_m) ** 2) / (4.0 * z[j])
            a_x, b_x = a_m, b_m
        a_in[j] = a_x
        b_in[j] = b_x
    return loss, damped


@njit(cache=True, inline="always")
def _keep(n_seg, lowpass, state, new_state, slot_of):
    """The step taken: the low-passes' new states kept, each segment's slot one step on
    (steps mod (N + 1), without a division)."""
    for j in range(n_seg.size):
        if lowpass[1, j] > 0.0:
            state[0, j], state[1, j] = new_state[0, j], new_state[1, j]
        slot_of[j] = slot_of[j] + 1 if slot_of[j] + 1 < n_seg[j] else 0


@njit(cache=True, inline="always")
def _junctions(buf, off, n_seg, z, c, rel, slot_of, a_in, b_in, top_speed, bottom_speed,
               upper, speed):
    """Departures of this step into the slots just read; returns the dashpot power of the
    interior junctions and of the relative dashpots across the parts between them. The top's
    speed is imposed (a top torque boundary would give it from the drive's inertia); the
    bottom moves with the BHA. A junction j's speed w_j balances the torques
    a_j-1 - z_j-1 w_j (from above) and b_j + z_j w_j (from below), its dashpot c_j-1 w_j and
    the relative dashpots rel (w_j-1 - w_j), rel (w_j - w_j+1) of the parts on either side:
    a tridiagonal system (the end parts carry none), solved by elimination (``upper``,
    ``speed``: scratch of the segments' size)."""
    m = n_seg.size
    buf[off[0] + slot_of[0]] = b_in[0] + 2.0 * z[0] * top_speed
    upper[0] = 0.0
    speed[0] = 0.0
    for j in range(1, m):
        denom = z[j - 1] + z[j] + c[j - 1] + rel[j - 1] + rel[j] - rel[j - 1] * upper[j - 1]
        upper[j] = rel[j] / denom
        speed[j] = (a_in[j - 1] - b_in[j] + rel[j - 1] * speed[j - 1]) / denom
    for j in range(m - 2, 0, -1):
        speed[j] += upper[j] * speed[j + 1]
    power = 0.0
    for j in range(1, m):
        om = speed[j]
        power += c[j - 1] * om * om
        if j < m - 1:
            power += rel[j] * (om - speed[j + 1]) ** 2
        buf[off[j - 1] + n_seg[j - 1] + slot_of[j - 1]] = a_in[j - 1] - 2.0 * z[j - 1] * om
        buf[off[j] + slot_of[j]] = b_in[j] + 2.0 * z[j] * om
    buf[off[m - 1] + n_seg[m - 1] + slot_of[m - 1]] = a_in[m - 1] - 2.0 * z[m - 1] * bottom_speed
    return power


@njit(cache=True, inline="always")
def _slide(r1, r2, d1, d2, cap):
    """The sliding speeds (u1, u2) of a station pushed by the free force (r1, r2) through the
    lines' resistances (d1, d2) against the wall's sliding friction ``cap`` (|r| > cap): the
    friction opposes u, so u_i = r_i/(d_i + lam) with lam = cap/|u|, the root of
    F(lam) = |(r_i lam/(d_i + lam))_i| - cap, increasing from F(0) = -cap; it lies between the
    isotropic roots d_min cap/(|r| - cap) and d_max cap/(|r| - cap). Newton from the left,
    safeguarded by that bracket, to 1e-14 (one to eight steps; the friction force is then
    r - d u)."""
    a1, a2 = abs(r1), abs(r2)
    excess = math.sqrt(a1 * a1 + a2 * a2) - cap
    lo, hi = min(d1, d2) * cap / excess, max(d1, d2) * cap / excess
    lam = lo
    for _ in range(100):
        e1, e2 = 1.0 / (d1 + lam), 1.0 / (d2 + lam)
        g1, g2 = a1 * lam * e1, a2 * lam * e2
        norm = math.sqrt(g1 * g1 + g2 * g2)
        f = norm - cap
        if f > 0.0:
            hi = lam
        else:
            lo = lam
        slope = (g1 * a1 * d1 * e1 * e1 + g2 * a2 * d2 * e2 * e2) / norm
        new = lam - f / slope if slope > 0.0 else 0.5 * (lo + hi)
        if not lo <= new <= hi:
            new = 0.5 * (lo + hi)
        if abs(new - lam) <= 1e-14 * lam or f == 0.0:
            lam = new
            break
        lam = new
    return r1 / (d1 + lam), r2 / (d2 + lam)


@njit(cache=True, inline="always")
def _free_speeds(m, sc, tr, ar, w_cols, row):
    """The stations' speeds with no wall, ``sc[SC_WS, 1..m-1]`` and ``sc[SC_WA, 1..m-1]``: each
    junction's balance of the arriving invariants, its dashpot and the relative dashpots
    (``_junctions``' tridiagonal system A w = a_in[j-1] - b_in[j]), by elimination with A's
    fixed factors (``w_cols[line, row]``: the upper factor by station, ``row + 1``: 1/pivot),
    both lines in one pass."""
    sc[SC_WS, 0] = sc[SC_WA, 0] = 0.0
    for j in range(1, m):
        sc[SC_WS, j] = ((sc[SC_TA, j - 1] - sc[SC_TB, j] + tr[j - 1] * sc[SC_WS, j - 1])
                        * w_cols[0, row + 1, j - 1])
        sc[SC_WA, j] = ((sc[SC_AA, j - 1] - sc[SC_AB, j] + ar[j - 1] * sc[SC_WA, j - 1])
                        * w_cols[1, row + 1, j - 1])
    for j in range(m - 2, 0, -1):
        sc[SC_WS, j] += w_cols[0, row, j - 1] * sc[SC_WS, j + 1]
        sc[SC_WA, j] += w_cols[1, row, j - 1] * sc[SC_WA, j + 1]


@njit(cache=True)
def _bha_on_wall(delta, slope, regime, v, om, ts, fb, rate, n, lam, beta, hs, hpsi, cap_s, cap_d,
                 kap, sigma, held, ft, fa):
    """The bit-rock laws with the rigid BHA rubbing on the wall: one Coulomb contact against
    the BHA's resultant sliding velocity (v, kappa omega), at most ``cap_d`` sliding [F*]; one
    at rest (``held``) stays there while ``cap_s`` holds the free force; in the scaled units of
    ``WallFriction``. The wall's torque ``ft`` [C] and force ``fa`` [F*] oppose the BHA's
    motion over the step: omega+ = omega + h (T_s - T - ft), likewise axially.

    The two laws are solved together by alternating them, each exactly for the other's last
    forces: the bit's set-valued laws (``_bit_rock_law``) under the pipe's torque and force
    less the wall's, then the wall's contact under the BHA's speeds free of the wall (the
    bit's forces held), until the wall's forces change by no more than 1e-12 of its capacity.
    Turning steadily (the bit's torque does not depend on the speed) that is two passes. As
    at the stations, a contact that breaks loose slides for the rest of the step. At rest
    against both the rock and the wall, the split of the load between them is not
    determined by a rigid BHA: the wall keeps the force it had and the rock's reaction takes
    the change, so the BHA breaks loose when the bit's break-away limit and the wall's static
    friction are both exceeded. Returns the laws' (regime, w, t, g, v+, omega+, event), then
    (ft, fa, held) as solved; a BHA held by the wall has its speeds exactly 0."""
    d_t, d_a = 1.0 / hs, 1.0 / hpsi                # the BHA's resistances to a step's change
    d2 = d_t * sigma / (kap * kap)
    tol_t, tol_a = 1e-12 * cap_s * kap / sigma, 1e-12 * cap_s
    loose = False
    hold = held
    for _ in range(WALL_SWEEPS):
        regime_new, w, t, g, v_new, om_new, event = _bit_rock_law(
            delta, slope, regime, v, om, ts - ft, fb - fa, rate, n, lam, beta, hs, hpsi)
        rt, ra = om_new * d_t + ft, v_new * d_a + fa     # the free torque and force
        r2 = rt * sigma / kap                            # torque -> tangential force [F*]
        if math.sqrt(ra * ra + r2 * r2) <= (cap_s if held and not loose else cap_d):
            hold = True
            nt, na = rt, ra
        else:
            hold = False
            loose = True
            va, u2 = _slide(ra, r2, d_a, d2, cap_d)
            nt, na = rt - (u2 / kap) * d_t, ra - va * d_a
        if abs(nt - ft) <= tol_t + 1e-12 * abs(nt) and abs(na - fa) <= tol_a + 1e-12 * abs(na):
            break
        ft, fa = nt, na
    if hold:
        v_new = om_new = 0.0
    return regime_new, w, t, g, v_new, om_new, event, ft, fa, hold


@njit(cache=True, inline="always")
def _junctions_wall(torsion, tslot, axial, aslot, om_top, om_bottom, v_top, v_bottom, wall,
                    stuck, sc):
    """``_junctions`` for both lines at once where the wall rubs: at each station the axial
    and the tangential sliding are one Coulomb contact (the friction against the resultant
    sliding velocity, at most mu n L_part; exact and set-valued: a station at rest stays there
    while the wall can hold the free force, static, one sliding stops when the sliding
    friction can), in the scaled units of ``WallFriction``.

    The stations are linear but for the wall: their speeds are the free ones less the wall's
    forces through the junctions' inverse, w = A^-1 (b - f), and only the K rubbing stations'
    columns of A^-1 are needed (``w_cols``, fixed, with A's elimination factors:
    ``wall_columns``). The K contacts, coupled
    through the relative dashpots, are solved by Gauss-Seidel sweeps over the contacts alone,
    each exactly for the others' forces, until a sweep's changes of force move no contact
    solved before them in the sweep by more than 1e-11 of the speeds (each contact's, or its
    speed free of the wall where it rests): every contact is then solved for the others'
    final forces. A contact at rest that breaks loose in a sweep slides for the rest of the
    step (held again only where the sliding friction can hold it): the law within the step is
    then monotone and the sweeps converge to its one solution (with the static threshold
    kept, a contact next to another can flip between rest and sliding from sweep to sweep,
    with no solution to settle on).

    ``stuck``: each station's state, updated. ``sc``: ``advance``'s scratch, read and written
    by row (no views: a view counts a reference to its array each step): the arriving
    invariants (SC_TA ..), the stations' speeds (SC_WS, SC_WA); the contacts' torques and axial
    forces (SC_FORCE, SC_FORCE + 1; kept from step to step, the next step's first guess), their
    speeds as the sweeps go (SC_NOW ..) and as each contact's own solution last left them, rest
    exactly 0 (SC_SOLVED ..).
    ``torsion``, ``axial``: the lines (``advance``), ``tslot``, ``aslot`` their slots; ``wall``
    the wall's friction (``advance``). Inlined, with at most 30 arguments (a call of more is
    compiled as one with *args, which is not inlined, and a call that is not inlined counts a
    reference to each of its arrays, atomically, on every step: a third of field_a's step).
    Returns the dashpots' powers and the wall's, (torsional, axial, wall torsional, wall axial)."""
    tz, tn, _, tc, tr, toff, tbuf, _, _ = torsion
    az, an, _, ac, ar, aoff, abuf, _, _ = axial
    w_static, w_dynamic, w_kappa, sigma, w_cols = wall
    m = tn.size
    tbuf[toff[0] + tslot[0]] = sc[SC_TB, 0] + 2.0 * tz[0] * om_top
    abuf[aoff[0] + aslot[0]] = sc[SC_AB, 0] + 2.0 * az[0] * v_top
    n_rub, at = w_cols.shape[1] - 2, m - 1      # a column: the stations, then the contacts
    _free_speeds(m, sc, tr, ar, w_cols, n_rub)
    coupled = False
    for j in range(m):
        if tr[j] > 0.0 or ar[j] > 0.0:
            coupled = True
    k = 0                                        # the contacts' speeds under the last forces
    for j in range(1, m):
        if w_static[j - 1] > 0.0:
            om, v = sc[SC_WS, j], sc[SC_WA, j]
            for q in range(n_rub):
                om -= w_cols[0, q, at + k] * sc[SC_FORCE, q]
                v -= w_cols[1, q, at + k] * sc[SC_FORCE + 1, q]
            sc[SC_NOW, k], sc[SC_NOW + 1, k] = om, v
            k += 1
    for _ in range(WALL_SWEEPS if coupled else 1):
        moved = 0.0
        scale = 1e-300
        k = 0
        for j in range(1, m):
            if w_static[j - 1] <= 0.0:
                continue
            gt, ga = w_cols[0, k, at + k], w_cols[1, k, at + k]    # the contact's own compliances
            dt, da = w_cols[0, n_rub, at + k], w_cols[1, n_rub, at + k]   # their inverses
            rt = sc[SC_NOW, k] * dt + sc[SC_FORCE, k]      # its free torque and axial force
            ra = sc[SC_NOW + 1, k] * da + sc[SC_FORCE + 1, k]
            kap, cap_s, cap_d = w_kappa[j - 1], w_static[j - 1], w_dynamic[j - 1]
            r2 = rt * sigma / kap                    # torque -> tangential force [F*]
            d2 = dt * sigma / (kap * kap)
            rn = math.sqrt(ra * ra + r2 * r2)
            if rn <= (cap_s if stuck[j - 1] else cap_d):
                om, v = 0.0, 0.0
            else:
                stuck[j - 1] = 0                     # broken loose: it slides this step
                v, u2 = _slide(ra, r2, da, d2, cap_d)
                om = u2 / kap
            dft, dfa = (rt - om * dt) - sc[SC_FORCE, k], (ra - v * da) - sc[SC_FORCE + 1, k]
            # the speeds' scale: the contact's own, or as free of the wall (one at rest)
            scale = max(scale, max(max(abs(om), abs(v)), max(abs(rt * gt), abs(ra * ga))))
            sc[SC_FORCE, k] += dft
            sc[SC_FORCE + 1, k] += dfa
            if coupled:                              # the others' speeds under the change
                for q in range(n_rub):
                    ct, ca = w_cols[0, k, at + q] * dft, w_cols[1, k, at + q] * dfa
                    sc[SC_NOW, q] -= ct
                    sc[SC_NOW + 1, q] -= ca
                    if q < k:                        # solved this sweep: now off by that
                        moved = max(moved, max(abs(ct), abs(ca)))
            sc[SC_NOW, k], sc[SC_NOW + 1, k] = om, v
            sc[SC_SOLVED, k], sc[SC_SOLVED + 1, k] = om, v
            k += 1
        if moved <= 1e-11 * scale:
            break
    for j in range(1, m):                        # every station under the contacts' forces
        for q in range(n_rub):
            sc[SC_WS, j] -= w_cols[0, q, j - 1] * sc[SC_FORCE, q]
            sc[SC_WA, j] -= w_cols[1, q, j - 1] * sc[SC_FORCE + 1, q]
    k = 0
    for j in range(1, m):                        # the contacts exactly as solved (rest: 0)
        if w_static[j - 1] > 0.0:
            sc[SC_WS, j], sc[SC_WA, j] = sc[SC_SOLVED, k], sc[SC_SOLVED + 1, k]
            k += 1
    power_t = power_a = wall_t = wall_a = 0.0
    k = 0
    for j in range(1, m):
        om, v = sc[SC_WS, j], sc[SC_WA, j]
        if w_static[j - 1] > 0.0:
            stuck[j - 1] = 1 if om == 0.0 and v == 0.0 else 0
            wall_t += sc[SC_FORCE, k] * om          # the wall's torque times the speed
            wall_a += sc[SC_FORCE + 1, k] * v       # (the balance's to the solve's 1e-11)
            k += 1
        power_t += tc[j - 1] * om * om
        power_a += ac[j - 1] * v * v
        if j < m - 1:
            power_t += tr[j] * (om - sc[SC_WS, j + 1]) ** 2
            power_a += ar[j] * (v - sc[SC_WA, j + 1]) ** 2
        tbuf[toff[j - 1] + tn[j - 1] + tslot[j - 1]] = sc[SC_TA, j - 1] - 2.0 * tz[j - 1] * om
        tbuf[toff[j] + tslot[j]] = sc[SC_TB, j] + 2.0 * tz[j] * om
        abuf[aoff[j - 1] + an[j - 1] + aslot[j - 1]] = sc[SC_AA, j - 1] - 2.0 * az[j - 1] * v
        abuf[aoff[j] + aslot[j]] = sc[SC_AB, j] + 2.0 * az[j] * v
    tbuf[toff[m - 1] + tn[m - 1] + tslot[m - 1]] = sc[SC_TA, m - 1] - 2.0 * tz[m - 1] * om_bottom
    abuf[aoff[m - 1] + an[m - 1] + aslot[m - 1]] = sc[SC_AA, m - 1] - 2.0 * az[m - 1] * v_bottom
    return power_t, power_a, wall_t, wall_a


# without numba's runtime (it allocates nothing): with it, every array a callee inlined in the
# loop takes is reference-counted, atomically, on each step, a fifth of a step without the
# wall and a third with it (field_a)
@njit(cache=True, _nrt=False)
def advance(x, k, surf, p, c, acc, torsion, axial, wall, work, n_steps, out, out_every,
            out_row):
    """Advance ``n_steps`` steps; rows every ``out_every`` steps (the lumped kernel's columns,
    then O_T_BOTTOM.. if ``out`` has them); return the next free row. A step that would turn
    the bit more than a sector is refused (K_REFUSED = 1), as in the lumped kernel.

    Parameters: the lumped kernel's arrays (``x`` .. ``acc``, sized for the distributed
    string: ``state_layout``); ``torsion`` and ``axial``, each line as the tuple (z: the
    segments' impedances, n: their slots per direction N + 1, f: the travel time's fraction,
    c: the dashpots, rel: the relative dashpots, off: the buffers' offsets, buf: the ring
    buffers, lowpass: the material low-passes' gains, state: their states); ``wall`` the
    wall's friction at the stations and the BHA (static and sliding capacities, kappa, sigma,
    the junctions' inverse ``wall_columns``); ``work`` the rig's own work arrays (the
    scratch, the slots each segment reads next, the stations held by the wall)."""
    tz, tn, tf, tc, tr, toff, tbuf, tlp, tstate = torsion
    az, an, af, ac, ar, aoff, abuf, alp, astate = axial
    w_static, w_dynamic, w_kappa, sigma, w_cols = wall
    scratch, slots, stuck = work
    n, lam, beta, h, psi = p[kn.P_N], p[kn.P_LAM], p[kn.P_BETA], p[kn.P_H], p[kn.P_PSI]
    inv_dth, dth = p[kn.P_INV_DTHETA], p[kn.P_DTHETA]
    w0, om0, v_min = c[kn.C_W0], c[kn.C_OMEGA0], c[kn.C_V_MIN]
    block, v_block = c[C_HOOK_POSITION] != 0.0, c[C_V_BLOCK]
    absorb, level = c[C_TOP_ABSORB] != 0.0, c[C_TOP_LEVEL]
    top_lo, top_hi = c[C_TOP_T_MIN], c[C_TOP_T_MAX]
    n_nodes = surf.shape[0]
    mask = n_nodes - 1
    sector = n_nodes * dth
    rows, extra = out.shape[0], out.shape[1] >= NOD
    mt, ma = tn.size, an.size
    zt_b, za_b = tz[mt - 1] + tc[mt - 1], az[ma - 1] + ac[ma - 1]
    ta_in, tb_in, aa_in, ab_in = scratch[0], scratch[1], scratch[2], scratch[3]
    tslot, aslot = slots[0], slots[1]
    t_next, a_next = scratch[6:8], scratch[8:10]     # the low-passes' states after a step
    ws, wa = scratch[4], scratch[5]                  # views made once, not per step
    for j in range(mt):                    # the slot each segment reads next: steps mod (N + 1)
        tslot[j] = k[kn.K_STEPS] % tn[j]
    for j in range(ma):
        aslot[j] = k[kn.K_STEPS] % an[j]
    k[kn.K_REFUSED] = 0
    (tau, u, v, phi, om, ptd, s_behind, hole, since_stick, w, t, delta, g, sum_w, sum_t, k_last,
     regime, a_om_min, a_om_max, a) = kn._load(x, k, acc)
    steps, sampled = k[kn.K_STEPS], k[kn.K_SAMPLED]
    dom, dv, a_prev = x[X_DOM], x[X_DV], x[X_A_PREV]
    t_bot, f_bot, v_top, f_top = x[X_T_BOTTOM], x[X_F_BOTTOM], x[X_V_TOP], x[X_F_TOP]
    a_w, a_tob = acc[kn.A_W], acc[kn.A_T]
    work_w, work_h = acc[kn.A_WORK_WEIGHT], acc[kn.A_WORK_HOIST]
    damp_r, damp_a = acc[A_DAMPED_ROT], acc[A_DAMPED_AX]
    loss_r, loss_a = acc[A_LOSS_ROT], acc[A_LOSS_AX]
    wall_r, wall_a = acc[A_WALL_ROT], acc[A_WALL_AX]
    rubs = w_cols.shape[1] > 2                       # the pipe's stations rub
    bha_s = w_static[mt - 1] if w_static.size > 0 else 0.0
    bha_rubs = bha_s > 0.0                           # the BHA's contact rubs
    bha_d = w_dynamic[mt - 1] if bha_rubs else 0.0
    bha_k = w_kappa[mt - 1] if bha_rubs else 1.0
    held = bha_rubs and stuck[mt - 1] != 0
    ft_w, fa_w = x[X_BHA_WALL_T], x[X_BHA_WALL_F]
    ts_top = x[kn.X_TS]
    # the top drive (kinematic: the ideal speed source omega0)
    mode = np.int64(p[kn.P_MODE])
    drive = mode != kn.MODE_KINEMATIC
    t_cmd = c[kn.C_T_CMD]
    t_max, t_min, kp, ki = p[kn.P_T_MAX], p[kn.P_T_MIN], p[kn.P_KP], p[kn.P_KI]
    c_end, c_mean = p[kn.P_LAG_END], p[kn.P_LAG_MEAN]
    rate_step = p[kn.P_RATE] * h
    z_top = tz[0]
    hj = h / p[kn.P_J]
    hj_top = hj / (1.0 + 0.5 * hj * z_top)        # the string's b + z Omega, trapezoidal
    om_td, integral, tm, ref, a_otd, a_tm, a_wm, work_td = _load_drive(x, acc)
    if not drive and not absorb:
        om_td = om0
    for _ in range(n_steps):
        lr, dr = _arrivals(tbuf, toff, tn, tf, tz, tslot, ta_in, tb_in, tlp, tstate, t_next)
        la, da = _arrivals(abuf, aoff, an, af, az, aslot, aa_in, ab_in, alp, astate, a_next)
        a_t, a_a = ta_in[mt - 1], aa_in[ma - 1]
        rate = (a_t - a_prev) / h          # the bottom torque's rate while the bit is held
        # the top: speed imposed or the drive's inertia under its motor torque; hook force w0
        # unless the drawworks' speed limit holds it, or (position) the block's speed
        om_top, integral_m, om_td_new, tm_new, ref_new, t_bar = om0, integral, om0, tm, ref, tm
        if drive:
            integral_m, om_td_new, tm_new, ref_new, t_bar = _drive_advance(
                mode, om_td, integral, tm, ref, tb_in[0] + z_top * om_td, om0, t_cmd, 0.5 * h,
                ki, rate_step, hj_top, kp, t_min, t_max, c_end, c_mean)
            om_top = 0.5 * (om_td + om_td_new)
        elif absorb:                       # the drive's inertia turned to reflect nothing
            om_td_new = (level - tb_in[0]) / (2.0 * z_top)     # by the step's end
            om_top = 0.5 * (om_td + om_td_new)
            t_bar = tb_in[0] + z_top * om_top + (om_td_new - om_td) / hj
            if t_bar > top_hi or t_bar < top_lo:               # the motor's limits: held
                t_bar = min(max(t_bar, top_lo), top_hi)
                om_td_new = om_td + hj_top * (t_bar - tb_in[0] - z_top * om_td)
                om_top = 0.5 * (om_td + om_td_new)
        ts_top = tb_in[0] + z_top * om_top
        if block:
            v_top = v_block
        else:
            v_top = (w0 - ab_in[0]) / az[0]
            if v_top < v_min:
                v_top = v_min
        f_top = ab_in[0] + az[0] * v_top
        # the BHA and the bit: the lumped kernel's step, taken in parts at the laws' switches
        hs, left, splits, om_int, v_int = h, h, 1, 0.0, 0.0
        refused = False
        while True:
            h2 = 0.5 * hs
            hpsi = hs * psi
            ts = a_t - zt_b * (om + h2 * dom)
            fb = a_a - za_b * (v + h2 * dv)
            u_m = u + h2 * v
            phi_m = phi + h2 * om
            s_m, slope = _surface_at(surf, mask, phi_m, inv_dth, k_last, s_behind)
            delta_new = u_m - s_m
            if bha_rubs:
                (regime_new, w_new, t_new, g_new, v_new, om_new, event, ft_new, fa_new,
                 held_new) = _bha_on_wall(delta_new, slope, regime, v, om, ts, fb, rate, n, lam,
                                          beta, hs, hpsi, bha_s, bha_d, bha_k, sigma, held,
                                          ft_w, fa_w)
            else:
                regime_new, w_new, t_new, g_new, v_new, om_new, event = _bit_rock_law(
                    delta_new, slope, regime, v, om, ts, fb, rate, n, lam, beta, hs, hpsi)
                ft_new, fa_new, held_new = 0.0, 0.0, False
            if splits < MAX_SPLITS and EVENT_MARGIN < event < 1.0 - EVENT_MARGIN:
                splits += 1
                hs *= event
                continue
            phi_new = phi_m + h2 * om_new
            if phi_new - phi > sector:
                refused = True
                break
            regime, w, t, g, delta = regime_new, w_new, t_new, g_new, delta_new
            ft_w, fa_w, held = ft_new, fa_new, held_new
            u_new = u_m + h2 * v_new
            k_last, s_behind, hole = _sweep(surf, mask, n_nodes, dth, inv_dth, k_last, s_behind,
                                            hole, phi, phi_new, u, u_new)
            om_bar, v_bar = 0.5 * (om + om_new), 0.5 * (v + v_new)
            a = _accumulate(a, hs, regime, om_bar, v_bar, w, t, ts_top, 0.0)
            damp_r += hs * tc[mt - 1] * (om + h2 * dom) * om_bar
            damp_a += hs * ac[ma - 1] * (v + h2 * dv) * v_bar
            wall_r += hs * ft_w * om_bar           # the wall's work on the BHA (0: no contact)
            wall_a += hs * fa_w * v_bar
            om_int += hs * om_bar
            v_int += hs * v_bar
            sum_w += w * (hs / h)
            sum_t += t * (hs / h)
            t_bot, f_bot = ts, fb
            dom = 0.0 if regime == REGIME_STUCK else (om_new - om) / hs
            dv = 0.0 if v_new == 0.0 else (v_new - v) / hs
            u, v, phi, om = u_new, v_new, phi_new, om_new
            tau += hs
            a_om_min = min(a_om_min, om)
            a_om_max = max(a_om_max, om)
            since_stick = 0.0 if regime == REGIME_STUCK else since_stick + hs
            left -= hs
            if left <= 0.0:
                break
            hs = left
        if refused:
            k[kn.K_REFUSED] = 1
            break
        damp_r += h * dr
        damp_a += h * da
        # the string: reflections at the BHA, junctions, the top
        if rubs:
            pt, pa, fw_t, fw_a = _junctions_wall(
                torsion, tslot, axial, aslot, om_top, om_int / h, v_top, v_int / h, wall, stuck,
                scratch)
            damp_r += h * pt
            damp_a += h * pa
            wall_r += h * fw_t
            wall_a += h * fw_a
        else:
            damp_r += h * _junctions(tbuf, toff, tn, tz, tc, tr, tslot, ta_in, tb_in, om_top,
                                     om_int / h, ws, wa)
            damp_a += h * _junctions(abuf, aoff, an, az, ac, ar, aslot, aa_in, ab_in, v_top,
                                     v_int / h, ws, wa)
        work_td += h * ts_top * om_top
        loss_r += h * lr
        loss_a += h * la
        work_w += h * w0 * v_top
        work_h += h * (f_top - w0) * v_top
        ptd += h * om_top
        a_otd += h * om_top
        if drive:
            a_tm += h * t_bar
            a_wm += h * t_bar * om_top
            integral = _integral_end(mode, integral, integral_m, 0.5 * h, ki, om0, om_td_new,
                                     t_min, t_max)
            om_td, tm, ref = om_td_new, tm_new, ref_new
        elif absorb:
            a_tm += h * t_bar
            a_wm += h * t_bar * om_top
            om_td, tm = om_td_new, t_bar
        else:                                  # the ideal source's torque is the string's
            a_tm += h * ts_top
            a_wm += h * ts_top * om0
        a_prev = a_t
        _keep(tn, tlp, tstate, t_next, tslot)
        _keep(an, alp, astate, a_next, aslot)
        steps += 1
        if out_row < rows and steps % out_every == 0:
            o = out[out_row]
            _write_row(o, tau, u, v, phi, om, ptd, sum_w, sum_t, steps - sampled, ts_top, delta,
                       regime, w0, om0, g, om_td, tm if drive else ts_top)
            if extra:
                o[O_T_BOTTOM], o[O_F_BOTTOM], o[O_V_TOP], o[O_F_TOP] = t_bot, f_bot, v_top, f_top
            out_row += 1
            a_w, a_tob, sum_w, sum_t = _fold_sample(h, a_w, a_tob, sum_w, sum_t)
            sampled = steps
    kn._store(x, k, acc, tau, u, v, phi, om, ptd, s_behind, hole, since_stick, w, t, delta, g,
              sum_w, sum_t, k_last, regime, a_om_min, a_om_max, a)
    x[kn.X_TS] = ts_top                      # _store wrote the lumped phi_td - phi
    x[X_T_BOTTOM], x[X_F_BOTTOM], x[X_V_TOP], x[X_F_TOP] = t_bot, f_bot, v_top, f_top
    x[X_DOM], x[X_DV], x[X_A_PREV] = dom, dv, a_prev
    x[X_BHA_WALL_T], x[X_BHA_WALL_F] = ft_w, fa_w
    if bha_rubs:
        stuck[mt - 1] = 1 if held else 0
    acc[kn.A_TIME] += (steps - k[kn.K_STEPS]) * h
    acc[kn.A_W0] += (steps - k[kn.K_STEPS]) * h * w0
    acc[kn.A_OMEGA0] += (steps - k[kn.K_STEPS]) * h * om0
    k[kn.K_STEPS], k[kn.K_SAMPLED] = steps, sampled
    acc[kn.A_W], acc[kn.A_T] = a_w, a_tob
    _store_drive(x, acc, om_td, integral, tm, ref, a_otd, a_tm, a_wm, work_td)
    acc[kn.A_WORK_WEIGHT], acc[kn.A_WORK_HOIST] = work_w, work_h
    acc[A_DAMPED_ROT], acc[A_DAMPED_AX] = damp_r, damp_a
    acc[A_LOSS_ROT], acc[A_LOSS_AX] = loss_r, loss_a
    acc[A_WALL_ROT], acc[A_WALL_AX] = wall_r, wall_a
    return out_row
