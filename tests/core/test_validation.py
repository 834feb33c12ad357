"""The simulator against theory (model contract, sections 4-6), each a number that would be
wrong if the physics or the numerics were. Run lengths are stated in units of t*."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from drill_sim.core import Groups, Simulator, steady_state
from drill_sim.core.kernel import REGIME_STUCK
from drill_sim.core.stability import stability


def _stationary_metrics(groups, w0, omega0, transient=600.0, window=600.0, dt=None):
    sim = Simulator(groups) if dt is None else Simulator(groups, dt)
    sim.start_steady(w0, omega0, 1e-3)
    sim.run(transient)
    sim.reset_window()
    sim.run(window)
    return sim


def test_exact_steady_start_stays_on_the_trivial_solution(base_groups, base_commands):
    """1. No perturbation: only round-off, growing at most like exp(Re s tau) from 1e-12."""
    w0, omega0 = base_commands
    st = steady_state(base_groups, w0, omega0)
    growth = stability(base_groups, w0, omega0).rightmost.real
    sim = Simulator(base_groups)
    sim.start_steady(w0, omega0)
    tr = sim.run(20.0, output_interval=0.1)
    bound = 1e-12 * np.exp(growth * tr.tau) + 1e-12
    for value, exact in ((tr.omega, omega0), (tr.v, st.v0), (tr.w, w0), (tr.ts, st.t0),
                         (tr.delta_n, st.delta_n0)):
        assert np.all(np.abs(value - exact) <= bound * max(1.0, abs(exact)))


# (groups, w0, omega0, run length, fit from): points where the perturbation of the delay (the
# k s^2 E term of Delta: a faster bit cuts a thinner chip) moves the rightmost root by 12 %, 30 %
# and 52 % in Re s (a simulator with a fixed delay tau_n0 would grow at the wrong rate), and
# where that root leads the next one by enough for a two-exponent fit.
GROWTH_POINTS = [(Groups(4, 13.73, 6.84, 0.36), 12.0, 4.0, 18.0, 8.0),
                 (Groups(3, 5.0, 3.0, 0.5), 15.0, 1.0, 24.0, 12.0),
                 (Groups(2, 3.0, 1.0, 0.5), 10.0, 1.0, 18.0, 8.0)]


def _root_with_a_fixed_delay(s: complex, groups: Groups, tau: float) -> complex:
    """Newton on Delta without the delay-perturbation term, (s^2+1)(s^2 + n psi E), from s."""
    npsi = groups.n * groups.psi
    for _ in range(100):
        ex = np.exp(-s * tau)
        f = (s * s + 1) * (s * s + npsi * (1 - ex))
        df = 2 * s * (s * s + npsi * (1 - ex)) + (s * s + 1) * (2 * s + npsi * tau * ex)
        s = s - f / df
    return s


@pytest.mark.parametrize("groups, w0, omega0, duration, fit_from", GROWTH_POINTS)
def test_small_perturbation_grows_like_the_rightmost_root(groups, w0, omega0, duration, fit_from):
    """2. Re s and Im s of the rightmost root, measured from the simulated bit speed (1e-3;
    the code achieves ~3e-5), at points where a fixed delay would be off by > 10 %."""
    res = stability(groups, w0, omega0)
    root = res.rightmost
    wrong = _root_with_a_fixed_delay(root, groups, res.steady.tau_n0)
    assert abs(wrong.real - root.real) > 0.1 * root.real        # the test can tell them apart
    sim = Simulator(groups)
    sim.start_steady(w0, omega0, 1e-9)
    tr = sim.run(duration, output_interval=0.01)
    late = tr.tau >= fit_from
    x = tr.omega[late] - omega0
    assert np.max(np.abs(x)) < 1e-3 * omega0          # still linear
    # order-2 linear prediction x[k+2] = c1 x[k+1] + c2 x[k] -> the dominant pair of exponents
    c1, c2 = np.linalg.lstsq(np.column_stack([x[1:-1], x[:-2]]), x[2:], rcond=None)[0]
    z = np.roots([1.0, -c1, -c2]).astype(complex)
    s = np.log(z[np.argmax(z.imag)]) / 0.01
    assert s.real == pytest.approx(root.real, rel=1e-3)
    assert abs(s.imag) == pytest.approx(abs(root.imag), rel=1e-3)


def test_averaged_invariants_in_stationary_stick_slip(base_groups, base_commands):
    """3. <Omega> = Omega0, <W> = W0 (stick reaction counted), <T> = <T_s>, within 1 %."""
    w0, omega0 = base_commands
    m = _stationary_metrics(base_groups, w0, omega0, transient=300.0, window=2000.0) \
        .window_metrics()
    assert m.stick_fraction > 0.2                      # genuinely stick-slip
    assert m.mean_bit_speed == pytest.approx(omega0, rel=0.01)
    assert m.mean_wob == pytest.approx(w0, rel=0.01)
    assert m.mean_tob == pytest.approx(m.mean_surface_torque, rel=0.01)
    # and the rate dependence of the mean torque: above the steady torque
    assert m.mean_surface_torque > steady_state(base_groups, w0, omega0).t0


def test_a_stuck_bit_breaks_free_when_the_string_torque_reaches_the_stick_law(base_groups,
                                                                              base_commands):
    """The stick law (model contract, section 2): a stuck bit pressed on the rock stays stuck
    while T_s <= n delta + beta lambda, cutting plus the wear flats' friction fully mobilised.
    In stick-slip, sampled every step, the string torque on the first step of each slip is
    that threshold to within one step's torque increase (Omega0 h while stuck). Catches a
    stick law without the friction term (off by beta lambda = 2.5 here) or with the wrong
    depth of cut."""
    g = base_groups
    w0, omega0 = base_commands
    sim = Simulator(g)
    sim.start_steady(w0, omega0, perturbation=1e-3)
    sim.run(300.0)                                   # into stationary stick-slip
    tr = sim.run(40.0, output_interval=sim.dt)
    release = np.nonzero(tr.stuck[:-1] & ~tr.stuck[1:])[0]
    assert release.size >= 3                         # several sticks in 40 t*
    threshold = g.n * tr.delta_n[release] + g.beta * g.lam
    assert np.abs(tr.ts[release] - threshold).max() <= 2.0 * omega0 * sim.dt


def test_ssi_is_the_spread_over_twice_the_mean_bit_speed(base_groups, base_commands):
    """The model's SSI is (max - min)/(2 mean) of the bit speed over the window: against
    the bit speed sampled every step over the same window (1e-3: a sampled mean)."""
    w0, omega0 = base_commands
    sim = Simulator(base_groups)
    sim.start_steady(w0, omega0, perturbation=1e-3)
    sim.run(300.0)
    sim.reset_window()
    tr = sim.run(30.0, output_interval=sim.dt)
    w = tr.omega
    m = sim.window_metrics()
    assert m.ssi == pytest.approx((w.max() - w.min()) / (2.0 * w.mean()), rel=1e-3)
    assert m.ssi > 1.0                               # stick-slip: the spread is large


@pytest.mark.parametrize("beta, sticks", [(0.36, True), (0.8, True), (1.2, False), (1.6, False)])
def test_stick_slip_only_if_beta_below_one(beta, sticks, base_commands):
    """4. base groups with beta varied, 1200 t* from a 1e-3 perturbation of steady drilling."""
    g = Groups(4, 13.73, 6.84, beta)
    m = _stationary_metrics(g, *base_commands).window_metrics()
    assert m.bounce_fraction == 0.0                    # the criterion is for kept contact
    if sticks:
        assert m.stick_fraction > 0.1 and m.min_bit_speed == 0.0
    else:
        assert m.stick_fraction == 0.0 and m.min_bit_speed > 0.5


TREND_SPEEDS = (0.5, 0.7, 1.0, 1.3, 1.7, 2.2, 3.0, 4.0)       # omega0, ~23 to 180 rpm on base
TREND_WEIGHTS = (7.5, 8.5, 9.6, 11.0, 13.0, 15.0)             # w0, 78 to 156 kN on base


def _rank_correlation(x, y) -> float:
    """Spearman's rho (no ties expected)."""
    def rank(a):
        return np.argsort(np.argsort(np.asarray(a, dtype=float), kind="stable"))
    return float(np.corrcoef(rank(x), rank(y))[0, 1])


@pytest.fixture(scope="module")
def stick_grid(base_groups):
    """Stick fraction over weights x speeds: 200 t* of transient, a 300 t* window, dt = 1e-3."""
    grid = np.empty((len(TREND_WEIGHTS), len(TREND_SPEEDS)))
    for i, w0 in enumerate(TREND_WEIGHTS):
        for j, omega0 in enumerate(TREND_SPEEDS):
            sim = _stationary_metrics(base_groups, w0, omega0, transient=200.0, window=300.0,
                                      dt=1e-3)
            grid[i, j] = sim.window_metrics().stick_fraction
    return grid


def test_stick_fraction_falls_as_speed_rises(stick_grid):
    """5a. Over the grid, at every weight with w0 - lambda >= 1.5: rank correlation with speed
    <= -0.7, and the slowest speed sticks more than 0.4, the fastest less than 0.1. Not pointwise
    monotonic: 0.36 at omega0 = 1.0 below 0.44 at 1.3 at 100 kN, and at w0 = 11, omega0 = 1.3 the
    run settles on a limit cycle that never sticks (SSI 0.76) beside the stick-slip the
    neighbouring points show (both exist: 4 digits of psi pick one or the other). Just above
    the friction weight (w0 = 7.5, lambda = 6.84) stick-slip is weak (< 0.25), with no trend."""
    for i, w0 in enumerate(TREND_WEIGHTS):
        row = stick_grid[i]
        if w0 < 8.0:
            assert np.all(row < 0.25), row
            continue
        assert _rank_correlation(TREND_SPEEDS, row) <= -0.7, (w0, row)
        assert row[0] > 0.4 and row[-1] < 0.1, (w0, row)


def test_stick_fraction_grows_as_weight_rises(stick_grid):
    """5b. Over the grid, at every speed: rank correlation with weight >= 0.6, and the heaviest
    weight sticks more than the lightest. Not pointwise monotonic either (0.84 at w0 = 13 above
    0.72 at 15, omega0 = 0.5)."""
    for j, omega0 in enumerate(TREND_SPEEDS):
        column = stick_grid[:, j]
        assert _rank_correlation(TREND_WEIGHTS, column) >= 0.6, (omega0, column)
        assert column[-1] > column[0], (omega0, column)


def test_beta_above_one_can_still_stick_at_a_hard_contact():
    """5c. A departure from the seed's 'stick-slip only if beta < 1', documented in
    msg_docs/model.md: with beta = 5 on the base groups, contact kept throughout, a bit pressed
    down (V > 0, g = 1) carries a wear-flat torque beta lambda = 34 above the string's ~30, so
    it is braked to a stop: it sticks about half the time. At beta <= 3 it never sticks."""
    for beta, sticks in ((3.0, False), (5.0, True)):
        sim = _stationary_metrics(Groups(4, 13.73, 6.84, beta), 9.6, 1.32, transient=200.0,
                                  window=300.0, dt=1e-3)
        m = sim.window_metrics()
        assert m.bounce_fraction == 0.0
        assert (m.stick_fraction > 0.3) if sticks else (m.stick_fraction == 0.0)


def test_power_balance(base_groups, base_commands):
    """6. Top-drive and weight work = bit dissipation + change of kinetic and spring energy."""
    w0, omega0 = base_commands
    sim = Simulator(base_groups)
    sim.start_steady(w0, omega0, 1e-3)
    sim.run(100.0)
    sim.reset_window()
    a = sim.state()
    m = sim.run(600.0).metrics
    b = sim.state()
    psi = base_groups.psi

    def rot(s):
        return 0.5 * s.omega**2 + 0.5 * (s.phi_td - s.phi) ** 2

    def ax(s):
        return 0.5 * s.v**2 / psi

    rot_in, ax_in = m.work_top_drive, m.work_weight + m.work_hoist
    assert m.dissipated_rotation + rot(b) - rot(a) == pytest.approx(rot_in, rel=5e-3)
    assert m.dissipated_axial + ax(b) - ax(a) == pytest.approx(ax_in, rel=5e-3)
    assert m.stick_fraction > 0.2


def test_bit_dissipation_follows_the_bit_laws(base_groups, base_commands):
    """6b. The power balance holds for any law (it checks bookkeeping); this checks the law. From
    the trajectory's own per-step outputs, the torque on a rotating bit must be the model's
    T = T_c + (a/2) mu gamma W_f with W_f = W - W_c, i.e. t = n delta + beta (w - n delta), and
    the rotational dissipation the kernel integrates must equal the sum of torque times mean
    speed built from that law (a stuck bit's torque is a reaction, taken as it is)."""
    w0, omega0 = base_commands
    g = base_groups
    sim = Simulator(g)
    sim.start_steady(w0, omega0, 1e-3)
    sim.run(100.0)
    sim.reset_window()
    omega_start = sim.state().omega
    tr = sim.run(60.0, output_interval=sim.dt)           # per-step values
    h = sim.dt
    nd = g.n * tr.delta_n
    omega_bar = 0.5 * (np.concatenate([[omega_start], tr.omega[:-1]]) + tr.omega)
    rotating = ~tr.stuck & ~tr.off_bottom
    assert np.count_nonzero(tr.stuck) > 1000 and np.count_nonzero(rotating) > 1000

    def expected(beta: float) -> float:
        torque = np.where(rotating, nd + beta * (tr.w - nd), tr.t)
        return float(np.sum(h * torque * omega_bar))

    dissipated = tr.metrics.dissipated_rotation
    # a step in which a law switches is taken in parts and its row reports the parts' mean
    # forces: the law holds exactly on the other rows, and the sum is off by ~1e-8
    previous_v = np.concatenate([[np.nan], tr.v[:-1]])
    previous_stuck = np.concatenate([[True], tr.stuck[:-1]])
    whole = rotating & ~previous_stuck & (np.sign(tr.v) == np.sign(previous_v))
    assert np.count_nonzero(rotating & ~whole) < 0.01 * np.count_nonzero(rotating)
    assert np.allclose(tr.t[whole], (nd + g.beta * (tr.w - nd))[whole], rtol=1e-12)
    assert expected(g.beta) == pytest.approx(dissipated, rel=1e-7)
    # a torque law with beta off by 5 % would be seen (friction is ~1/4 of the torque)
    assert abs(expected(1.05 * g.beta) / dissipated - 1.0) > 1e-3


def test_convergence_in_dt(base_groups, base_commands, capsys):
    """7. Halving the default dt moves stationary metrics < 0.5 %; order observed on a transient."""
    from drill_sim.core.simulator import DEFAULT_DT
    w0, omega0 = base_commands
    metrics = []
    for dt in (DEFAULT_DT, DEFAULT_DT / 2):
        m = _stationary_metrics(base_groups, w0, omega0, transient=300.0, window=600.0, dt=dt) \
            .window_metrics()
        metrics.append(np.array([m.stick_fraction, m.max_bit_speed, m.mean_surface_torque,
                                 m.ssi]))
    change = np.abs(metrics[1] - metrics[0]) / np.abs(metrics[1])
    assert np.all(change < 5e-3), change
    # transient: 6 t* from a 1 % perturbation (smooth, no stick yet), end states compared
    ends = []
    for dt in (2e-3, 1e-3, 5e-4):
        sim = Simulator(base_groups, dt)
        sim.start_steady(w0, omega0, 1e-2)
        sim.run(6.0)
        s = sim.state()
        ends.append(np.array([s.u, s.v, s.phi, s.omega]))
    order = math.log2(np.linalg.norm(ends[0] - ends[1]) / np.linalg.norm(ends[1] - ends[2]))
    with capsys.disabled():
        print(f"\n  observed order of convergence on a smooth transient: {order:.2f}; "
              f"stationary metric change on halving dt: {np.max(change):.2e}")
    assert order > 1.5


def _observed_order(groups, w0, omega0, duration):
    """(order, scatter): slope of log error against log dt of the end state (u, v, phi, Omega)
    after ``duration`` from a 1 % perturbation, 14 steps from 4e-3 to 1e-4 t* against a
    1.5e-5 t* step, and the spread of log error about that line."""
    def end(n_steps: int) -> np.ndarray:
        sim = Simulator(groups, duration / n_steps)
        sim.start_steady(w0, omega0, 1e-2)
        sim.advance(n_steps)
        s = sim.state()
        return np.array([s.u, s.v, s.phi, s.omega])

    counts = np.unique(np.round(np.geomspace(duration / 4e-3, duration / 1e-4, 14)).astype(int))
    reference = end(round(duration / 1.5e-5))
    errors = np.log([np.linalg.norm(end(c) - reference) for c in counts])
    fit = np.polyfit(np.log(counts), errors, 1)
    return -fit[0], float(np.std(errors - np.polyval(fit, np.log(counts))))


def _transitions(groups, w0, omega0, duration) -> tuple[int, int]:
    """(stick onsets, losses of contact) within ``duration`` from the same start."""
    sim = Simulator(groups, 1e-4)
    sim.start_steady(w0, omega0, 1e-2)
    tr = sim.run(duration, output_interval=1e-4)
    return (int(np.count_nonzero(np.diff(tr.stuck.astype(int)) == 1)),
            int(np.count_nonzero(np.diff(tr.off_bottom.astype(int)) == 1)))


@pytest.mark.parametrize("case", ["stick-slip", "bouncing"])
def test_second_order_through_switches_of_the_laws(case, base_groups, base_commands, capsys):
    """7b. A law that switches inside a step (the bit stops turning, breaks away, its wear
    flats lift off or land, it leaves the rock or lands) is located there, and the scheme stays
    second order through it: through three stick phases on base (50 t*), and through the first
    losses of contact of the bouncing regime (7.5 t*; later, grazing contacts and chaos part
    the trajectories of different steps, and only statistics converge). Unlocated: 1.7 and
    1.2, the errors scattered about the fit by 0.97 (stick-slip)."""
    if case == "stick-slip":
        groups, (w0, omega0), duration = base_groups, base_commands, 50.0
        sticks, losses = _transitions(groups, w0, omega0, duration)
        assert sticks >= 3 and losses == 0
    else:
        groups, w0, omega0, duration = Groups(4, 50.0, 2.0, 0.36), 6.0, 3.0, 7.5
        sticks, losses = _transitions(groups, w0, omega0, duration)
        assert losses >= 3
    order, scatter = _observed_order(groups, w0, omega0, duration)
    with capsys.disabled():
        print(f"\n  observed order, {case}: {order:.2f} (scatter about the fit: {scatter:.2f} "
              "in log error)")
    assert order >= 1.8
    assert scatter < 0.4


def test_bouncing_regime(capsys):
    """8. Loss of contact: the rock surface never rises, mean ROP stays positive, no NaN."""
    g = Groups(4, 50.0, 2.0, 0.36)
    sim = Simulator(g)
    sim.start_steady(6.0, 3.0, 1e-3)
    sim.run(100.0)
    sim.reset_window()
    for _ in range(20):
        before = sim.surface
        tr = sim.run(10.0, output_interval=0.01)
        assert np.all(sim.surface >= before)
        assert np.all(np.isfinite(tr.omega)) and np.all(np.isfinite(tr.u))
    m = sim.window_metrics()
    assert m.bounce_fraction > 0.05
    assert m.mean_rop > 0


def test_a_bit_that_stops_turning_while_rising_keeps_rising(base_groups):
    """8b. The one-way axial hold (model contract 2.2, a choice): the rock pushes but cannot
    pull, so a bit stuck while moving up is not held: it coasts up against the weight with no
    reaction (W = 0), and only once it comes back down is it stopped, where it then rests,
    v^2/(2 psi w0) above where it stopped turning. A two-way hold would stop it at once."""
    sim = Simulator(base_groups)
    sim.start_steady(9.6, 1.32)
    sim.advance(1000)
    s = sim.state()
    v_up, w0 = -1.0, 1.0
    sim.place(replace(s, v=v_up, omega=0.0, phi_td=s.phi + 1.0, regime=REGIME_STUCK,
                      since_stick=0.0), steps=sim.steps, surface=sim.surface)
    sim.set_commands(w0, 0.0)                      # top drive stopped: the twist stays at 1
    tr = sim.run(0.2, output_interval=sim.dt)
    assert np.all(tr.stuck) and np.all(tr.omega == 0.0) and np.all(tr.delta_n > 0.0)
    rising = tr.v < 0.0
    assert 100 < np.count_nonzero(rising) < tr.v.size - 100
    assert np.all(tr.w[rising] == 0.0)                              # no pull from the rock
    assert np.allclose(np.diff(tr.v[rising]), sim.dt * base_groups.psi * w0)   # free coasting
    assert np.all(tr.v[~rising] == 0.0) and np.all(tr.u[~rising] == tr.u[-1])  # then held
    rise = s.u - tr.u[-1]
    assert rise == pytest.approx(v_up**2 / (2 * base_groups.psi * w0), rel=0.02)


def test_bouncing_statistics_are_stable_where_trajectories_are_not():
    """8c. The bouncing regime is chaotic (a 1e-6 change of the start moves the stick fraction
    by a few hundredths, the largest bit speed by a factor 2), so it is tested by statistics
    over an ensemble of starts: stick 0.45-0.65, bounce 0.09-0.16, ~1 % of the stuck time spent
    rising under the one-way hold (W = 0 there), mean WOB = w0, ROP > 0 in every member."""
    g = Groups(4, 50.0, 2.0, 0.36)
    sticks, bounces, rising_shares = [], [], []
    for k in range(4):
        sim = Simulator(g, 1e-3)
        sim.start_steady(6.0, 3.0, 1e-3 * (1.0 + 1e-6 * k))
        sim.run(100.0)
        sim.reset_window()
        tr = sim.run(300.0, output_interval=sim.dt)
        m = tr.metrics
        rising = tr.stuck & (tr.v < 0.0)
        held = rising & np.concatenate([[False], rising[:-1]])   # the whole step stuck, rising
        assert np.count_nonzero(held) > 0.5 * np.count_nonzero(rising)
        assert np.all(tr.w[held] == 0.0)
        assert m.mean_wob == pytest.approx(6.0, rel=1e-3) and m.mean_rop > 1.5
        sticks.append(m.stick_fraction)
        bounces.append(m.bounce_fraction)
        rising_shares.append(np.count_nonzero(rising) / np.count_nonzero(tr.stuck))
    assert np.ptp(sticks) > 0.01                    # the members do differ ...
    assert 0.45 < np.mean(sticks) < 0.65 and np.all(np.array(sticks) > 0.4)   # ... not their
    assert 0.09 < np.mean(bounces) < 0.16                                      # statistics
    assert 0.003 < np.mean(rising_shares) < 0.03


def test_tag_bottom_from_rest():
    """9. Spin up off bottom, slack off onto the rock: drilling starts; Omega >= 0 in contact."""
    g = Groups(4, 13.73, 6.84, 0.36)
    sim = Simulator(g)
    sim.start_at_rest(gap=3.0)

    def schedule(tau):
        omega0 = min(1.32, 1.32 * tau / 10.0)                  # spin up over 10 t*
        w0 = 0.0 if tau < 15 else min(9.6, 9.6 * (tau - 15) / 30.0)   # slack off from 15 t*
        return w0, omega0

    tr = sim.run(300.0, output_interval=sim.dt, schedule=schedule, schedule_interval=0.05)
    in_contact = ~tr.off_bottom
    assert np.all(tr.omega[in_contact] >= 0.0)
    assert np.all(tr.off_bottom[tr.tau < 15.0])                # hanging until slack-off
    assert tr.u[-1] > 20.0                                      # drilled several L*
    late = tr.tau > 200
    assert np.mean(tr.v[late]) > 0.3 * steady_state(g, 9.6, 1.32).v0
