"""The dimensionless stepper: fixed-size state, commands held between calls, window metrics.

``Simulator`` owns the state arrays of the kernel and is what the ROS node advances every tick.
``Simulator.run`` is the offline driver, returning a ``Trajectory`` with named columns.
All quantities here are dimensionless (model contract, section 3); ``drill_sim.core.rig``
converts.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from . import kernel as kn
from .metrics import Metrics
from .parameters import Groups, ParameterError, check_number
from .resolution import (
    MAX_NODES,
    STEPS_PER_PERIOD,
    fastest_period,
    max_step,
    resolves,
    surface_nodes,
)
from .stability import SteadyState, steady_state
from .top_drive import DriveGroups
from .trajectory import StateView, Trajectory

DEFAULT_DT = 5e-4            # [t*]; halving it moves stationary metrics ~2e-5 (test_validation)
class Simulator:
    """Fixed-step integration of the RGD model in dimensionless form.

    dt: step [t*]. stick_window: how long the stick-slip flag stays up after a stick [t*];
    default two torsional periods (4 pi). hoist_speed_limit: the string rises no faster [L*/t*].
    drive: the top drive (default kinematic: the seed's ideal speed source).
    """

    def __init__(self, groups: Groups, dt: float = DEFAULT_DT, *, stick_window: float = 4 * math.pi,
                 hoist_speed_limit: float = math.inf, nodes: int | None = None,
                 drive: DriveGroups | None = None) -> None:
        self.groups = groups
        self.dt = check_number("dt", dt, high=0.05)
        drive = DriveGroups() if drive is None else drive
        self._check_step(drive)
        self.stick_window = check_number("stick_window", stick_window)
        nodes = surface_nodes(groups, self.dt) if nodes is None else int(nodes)
        if nodes < 4 or nodes & (nodes - 1) or nodes > MAX_NODES:
            raise ParameterError(f"nodes = {nodes} is out of range: expected a power of two "
                                 f"4..{MAX_NODES}")
        dtheta = 2.0 * math.pi / groups.n / nodes
        self._p = np.zeros(kn.NP)
        self._p[:kn.P_MODE] = (groups.n, groups.psi, groups.lam, groups.beta, self.dt, dtheta,
                               1.0 / dtheta)
        self.rock = (1.0, groups.lam, groups.beta)   # set_rock
        self._x = np.zeros(kn.NX)
        self._k = np.zeros(kn.NK, dtype=np.int64)
        self._surf = np.zeros(nodes)
        self._c = np.zeros(kn.NC)
        self._acc = np.zeros(kn.NA)
        self._no_rows = np.zeros((0, kn.NO))
        self.drive = drive
        self._write_drive(drive)
        self.set_hoist_speed_limit(hoist_speed_limit)
        self.start_at_rest()

    def _check_step(self, drive: DriveGroups) -> None:
        if not resolves(self.groups, drive, self.dt):
            g = self.groups
            raise ParameterError(
                f"dt = {self.dt:g} t* cannot resolve the fastest mode: its period is "
                f"{fastest_period(g, drive):.4g} t* (axial 2 pi/sqrt(n psi) with n psi = "
                f"{g.n * g.psi:g}; torsional 2 pi/{drive.fastest_frequency():.4g}); expected "
                f"dt <= {max_step(g, drive):.4g} t*, {STEPS_PER_PERIOD} steps a period")

    # ---- initial conditions -------------------------------------------------------------
    def start_steady(self, w0: float, omega0: float, perturbation: float = 0.0) -> None:
        """The exact steady start (model contract, section 4); omega scaled by 1 + perturbation."""
        perturbation = check_number("perturbation", perturbation, low=-1.0)
        st = self.steady(w0, omega0)
        d = self.drive
        if not d.holds(st.t0):
            raise ParameterError(f"steady drilling needs a motor torque of {st.t0:.4g} C, outside "
                                 f"the drive's limits [{d.t_min:.4g}, {d.t_max:.4g}] C")
        self.set_commands(w0, omega0)
        nodes = self._surf.size
        dtheta = self._p[kn.P_DTHETA]
        theta = np.arange(nodes) * dtheta
        self._surf[:] = st.v0 * (theta - 2.0 * math.pi / self.groups.n) / st.omega0
        self._surf[0] = 0.0
        self._x[:] = 0.0                       # X_HOLE = 0: the deepest point is under the bit
        self._x[kn.X_V] = st.v0
        self._x[kn.X_OMEGA] = st.omega0 * (1.0 + perturbation)
        self._x[kn.X_PHI_TD] = st.t0
        self._x[kn.X_S_BEHIND] = -st.delta_n0
        self._x[kn.X_SINCE_STICK] = math.inf
        self._x[kn.X_W] = w0
        self._x[kn.X_T] = self._x[kn.X_TS] = st.t0
        self._x[kn.X_DELTA] = st.delta_n0
        self._x[kn.X_G] = 1.0
        x = self._x      # the drive turns at omega0 under the steady torque; the PI's error is 0
        x[kn.X_OMEGA_TD] = omega0
        x[kn.X_TM] = x[kn.X_TREF] = x[kn.X_DRIVE_I] = st.t0
        self._c[kn.C_T_CMD] = st.t0
        self._k[:] = (0, kn.REGIME_ROTATING, 0, 0, 0)
        self.reset_window()

    # ---- the rock ---------------------------------------------------------------------
    def set_rock(self, cutting: float = 1.0, lam: float | None = None,
                 beta: float | None = None) -> None:
        """The rock the bit cuts from now on (a formation along the hole), in this simulator's
        scales, which stay: ``cutting`` the intrinsic specific energy over the one the scales
        were made with (the cutting forces n delta times it), ``lam`` and ``beta`` the wear
        flats' groups (None: the simulator's ``groups``')."""
        cutting = check_number("cutting", cutting)
        lam = self.groups.lam if lam is None else check_number("lambda", lam, low_inclusive=True)
        beta = self.groups.beta if beta is None else check_number("beta", beta,
                                                                   low_inclusive=True)
        self.rock = (cutting, lam, beta)
        self._p[kn.P_N] = self.groups.n * cutting
        self._p[kn.P_LAM], self._p[kn.P_BETA] = lam, beta

    def steady(self, w0: float, omega0: float) -> SteadyState:
        """Steady drilling at (w0, omega0) in the rock being cut (``set_rock``): the model
        contract's steady state of that rock's own scaling, its lengths in this one's."""
        cutting, lam, beta = self.rock
        st = steady_state(replace(self.groups, lam=lam, beta=beta), w0, omega0)
        if cutting == 1.0:
            return st
        return replace(st, delta_n0=st.delta_n0 / cutting, v0=st.v0 / cutting)

    def start_at_rest(self, gap: float = 0.0) -> None:
        """Bit at rest ``gap`` [L*] above a flat bottom, string relaxed, commands zero."""
        gap = check_number("gap", gap, low_inclusive=True)
        self.set_commands(0.0, 0.0)
        self._c[kn.C_T_CMD] = 0.0
        self._surf[:] = 0.0
        self._x[:] = 0.0
        self._x[kn.X_U] = -gap
        self._x[kn.X_SINCE_STICK] = math.inf
        self._k[:] = (0, kn.REGIME_OFF_BOTTOM if gap > 0.0 else kn.REGIME_STUCK, 0, 0, 0)
        self.reset_window()

    def load_state(self, *, tau: float, steps: int, u: float, v: float, phi: float, omega: float,
                   phi_td: float, surface: np.ndarray, regime: int, since_stick: float,
                   w: float = 0.0, t: float = 0.0, delta_n: float = 0.0, g: float = 0.0,
                   surface_behind: float | None = None, omega_td: float | None = None,
                   motor_torque: float | None = None, drive_integral: float | None = None,
                   drive_reference: float | None = None) -> None:
        """Put the bit, string and rock in a given state (dimensionless).

        ``surface`` is S over one sector at any even spacing (node 0 at the sector's start), as
        ``surface`` reads it, and is resampled onto this simulator's nodes. The blades' current
        pass has already cut the last node they passed (the node at or below phi); its value
        from before the pass, which the next depth of cut is measured against, is
        ``surface_behind`` (as ``surface_behind`` reads it; None: the given value, i.e. that
        node was not cut by the current pass). w, t, delta_n and g are what the last step's
        outputs read until the next step; the force sums of the next sample start from here.
        The top drive: its speed (None: the speed command), motor torque (None: the string's,
        phi_td - phi), the PI's integral term and the limited reference (None: the motor
        torque); kinematic mode keeps the top drive at the speed command whatever is given.
        """
        values = np.array([tau, u, v, phi, omega, phi_td, since_stick], dtype=float)
        if not np.all(np.isfinite(values[:6])) or not np.all(np.isfinite(surface)):
            raise ParameterError("load_state: the state must be finite")
        self.take_force_sums()            # the window keeps the steps before the load
        src = np.asarray(surface, dtype=float)
        before = src.copy()               # the surface as the current pass found it
        if surface_behind is not None:
            before[math.floor(phi * src.size * self.groups.n / (2.0 * math.pi)) % src.size] = \
                check_number("surface_behind", surface_behind, low=None)
        nodes = self._surf.size
        x_src = np.arange(src.size + 1) / src.size
        x_dst = np.arange(nodes) / nodes
        self._surf[:] = np.interp(x_dst, x_src, np.append(src, src[0]))
        k_last = math.floor(phi * self._p[kn.P_INV_DTHETA])
        k_node = k_last & (nodes - 1)
        x = self._x
        x[kn.X_TAU], x[kn.X_U], x[kn.X_V], x[kn.X_PHI], x[kn.X_OMEGA], x[kn.X_PHI_TD] = values[:6]
        x[kn.X_SINCE_STICK] = since_stick
        x[kn.X_HOLE] = float(self._surf.max())
        x[kn.X_TS] = phi_td - phi
        x[kn.X_W], x[kn.X_T], x[kn.X_DELTA], x[kn.X_G] = w, t, delta_n, g
        x[kn.X_S_BEHIND] = float(np.interp(x_dst[k_node], x_src, np.append(before, before[0])))
        x[kn.X_SUM_W] = x[kn.X_SUM_T] = 0.0
        tm = phi_td - phi if motor_torque is None else motor_torque
        x[kn.X_OMEGA_TD] = self._c[kn.C_OMEGA0] if omega_td is None or \
            self.drive.mode == "kinematic" else omega_td
        x[kn.X_TM] = tm
        x[kn.X_DRIVE_I] = tm if drive_integral is None else drive_integral
        x[kn.X_TREF] = tm if drive_reference is None else drive_reference
        self._k[:] = (k_last, regime, steps, steps, 0)

    # ---- commands -----------------------------------------------------------------------
    def set_commands(self, w0: float, omega0: float) -> None:
        """Available weight w0 = W0/F* (any sign) and top-drive speed omega0 >= 0, held from now.

        A speed that would turn the bit more than a sector 2 pi/n in one step is refused."""
        w0 = check_number("w0", w0, low=None)
        omega0 = check_number("omega0", omega0, low_inclusive=True,
                              high=2.0 * math.pi / self.groups.n / self.dt)
        self._c[kn.C_W0], self._c[kn.C_OMEGA0] = w0, omega0   # both valid, or neither set
        if self.drive.mode == "kinematic":
            self._x[kn.X_OMEGA_TD] = omega0

    def set_motor_torque(self, torque: float) -> None:
        """The motor torque command [C] (torque mode), held from now; the drive's limits, rate
        limit and lag act on it."""
        self._c[kn.C_T_CMD] = check_number("motor torque", torque, low=None)

    @property
    def motor_torque_command(self) -> float:
        return float(self._c[kn.C_T_CMD])

    def set_drive(self, drive: DriveGroups) -> None:
        """Change the top drive at run time, the state kept. A change of mode is bumpless: the
        motor torque starts from the torque the top drive was applying (from kinematic mode,
        the string's), the speed PI's integral term so that its output is that torque, and the
        torque command (into torque mode) is that torque; into kinematic mode the top drive
        takes the speed command at once. Refused, nothing changed, if dt cannot resolve it."""
        self._check_step(drive)
        x, c, old = self._x, self._c, self.drive
        if drive.mode != old.mode:
            if old.mode == "kinematic":
                x[kn.X_OMEGA_TD] = c[kn.C_OMEGA0]
                x[kn.X_TM] = x[kn.X_TREF] = x[kn.X_TS]
            if drive.mode == "torque":
                c[kn.C_T_CMD] = x[kn.X_TM]
            elif drive.mode == "speed":
                error = c[kn.C_OMEGA0] - x[kn.X_OMEGA_TD]
                x[kn.X_DRIVE_I] = min(max(x[kn.X_TREF] - drive.kp * error, drive.t_min),
                                      drive.t_max)
            else:
                x[kn.X_OMEGA_TD] = c[kn.C_OMEGA0]
        self.drive = drive
        self._write_drive(drive)

    def _write_drive(self, d: DriveGroups) -> None:
        self._advance = kn.stepper(d.code)
        p = self._p
        p[kn.P_MODE], p[kn.P_J], p[kn.P_T_MAX], p[kn.P_T_MIN] = d.code, d.j, d.t_max, d.t_min
        p[kn.P_RATE], p[kn.P_LAG], p[kn.P_KP], p[kn.P_KI] = d.rate, d.lag, d.kp, d.ki
        p[kn.P_LAG_END], p[kn.P_LAG_MEAN] = d.lag_weights(self.dt)

    def set_hoist_speed_limit(self, limit: float) -> None:
        """Fastest upward axial speed [L*/t*]; math.inf for none (the pure model)."""
        if limit != math.inf:
            limit = check_number("hoist_speed_limit", limit)
        self._c[kn.C_V_MIN] = -limit

    @property
    def commands(self) -> tuple[float, float]:
        return float(self._c[kn.C_W0]), float(self._c[kn.C_OMEGA0])

    # ---- stepping -----------------------------------------------------------------------
    def advance(self, n_steps: int) -> None:
        """Advance ``n_steps`` steps with the commands held; allocation-free.

        Raises ParameterError, the state left after the last step taken, before a step that
        would turn the bit more than a sector (see ``kernel.advance``)."""
        self._advance(self._x, self._k, self._surf, self._p, self._c, self._acc, n_steps,
                      self._no_rows, 1, 0)
        if self._k[kn.K_REFUSED]:
            self._refuse_step()

    def _refuse_step(self) -> None:
        sector = 2.0 * math.pi / self.groups.n
        raise ParameterError(
            f"at tau = {self.tau:.6g} the next step (dt = {self.dt:g}) would turn the bit more "
            f"than a sector 2 pi/n = {sector:.4g} rad, from bit speed {self._x[kn.X_OMEGA]:.4g}: "
            "the rock surface cannot be swept nor the depth of cut measured; use a smaller dt "
            "or less weight on bit (the string winds up to about w0, and the bit slips at "
            "about that speed); the state is kept at the last step")

    def advance_into(self, n_steps: int, out: np.ndarray, every: int, row: int) -> int:
        """Advance and write a row to ``out`` at every step count that is a multiple of ``every``;
        return the next free row. A row is a sample: its w and t are the means over the steps
        since the previous sample (a row, ``take_force_sums``, ``start_sample``, a start)."""
        row = int(self._advance(self._x, self._k, self._surf, self._p, self._c, self._acc,
                                n_steps, out, every, row))
        if self._k[kn.K_REFUSED]:
            self._refuse_step()
        return row

    def start_sample(self) -> None:
        """The next sample's (row's) w and t average over the steps from now on."""
        self.take_force_sums()

    def run(self, duration: float, *, output_interval: float | None = None,
            schedule: Callable[[float], tuple[float, float]] | None = None,
            schedule_interval: float | None = None,
            progress: Callable[[float], None] | None = None) -> Trajectory:
        """Advance by ``duration`` [t*] recording rows every ``output_interval`` [t*] (None: none).

        ``schedule(tau) -> (w0, omega0)`` is applied every ``schedule_interval`` [t*] (zero-order
        hold); ``progress(fraction)`` is called between chunks. Each row's w and t are the means
        over its output interval (the first row's: since the run started), as a sensor sampled
        at that interval would report the impulse of a stick or a landing; with
        ``output_interval = dt`` they are the per-step values. A run starts a new sample.
        """
        duration = check_number("duration", duration)
        n_total = round(duration / self.dt)
        if output_interval is None:
            every, out = 1, self._no_rows
        else:
            every = max(1, round(check_number("output_interval", output_interval) / self.dt))
            out = np.empty((n_total // every + 1, kn.NO))
        chunk = n_total if schedule is None else max(1, round(schedule_interval / self.dt))
        chunk = min(chunk, 2_000_000) if progress is not None else chunk
        row, done = 0, 0
        self.start_sample()
        while done < n_total:
            if schedule is not None:
                self.set_commands(*schedule(self.tau))
            n = min(chunk, n_total - done)
            row = self.advance_into(n, out, every, row)
            done += n
            if progress is not None:
                progress(done / n_total)
        return Trajectory.from_rows(out[:row], self.window_metrics())

    # ---- observation --------------------------------------------------------------------
    @property
    def tau(self) -> float:
        return float(self._x[kn.X_TAU])

    @property
    def steps(self) -> int:
        return int(self._k[kn.K_STEPS])

    @property
    def regime(self) -> int:
        """kernel.REGIME_* of the last step."""
        return int(self._k[kn.K_REGIME])

    @property
    def live_state(self) -> np.ndarray:
        """The kernel's state vector itself (indexed by kernel.X_*), not a copy: the cheapest
        read for a caller sampling every tick. Read it; never write it."""
        return self._x

    def state(self) -> StateView:
        x, k = self._x, self._k
        return StateView(tau=x[kn.X_TAU], u=x[kn.X_U], v=x[kn.X_V], phi=x[kn.X_PHI],
                         omega=x[kn.X_OMEGA], phi_td=x[kn.X_PHI_TD], w=x[kn.X_W], t=x[kn.X_T],
                         ts=x[kn.X_TS], delta_n=x[kn.X_DELTA], g=x[kn.X_G],
                         regime=int(k[kn.K_REGIME]), since_stick=x[kn.X_SINCE_STICK],
                         omega_td=x[kn.X_OMEGA_TD],
                         motor_torque=x[kn.X_TS if self.drive.mode == "kinematic" else kn.X_TM],
                         drive_integral=x[kn.X_DRIVE_I], drive_reference=x[kn.X_TREF])

    def take_force_sums(self) -> tuple[float, float, int]:
        """(sum of w, sum of t, steps) over the steps since the previous sample (a call, an
        output row, a start or ``load_state``), and start the next: a sample's mean WOB and TOB
        are the sums over the steps (see ``Rig.sample``)."""
        x, k, acc, h = self._x, self._k, self._acc, self.dt
        sums = (float(x[kn.X_SUM_W]), float(x[kn.X_SUM_T]), int(k[kn.K_STEPS] - k[kn.K_SAMPLED]))
        acc[kn.A_W] += h * sums[0]              # the window's integrals take the sample in
        acc[kn.A_T] += h * sums[1]
        x[kn.X_SUM_W] = x[kn.X_SUM_T] = 0.0
        k[kn.K_SAMPLED] = k[kn.K_STEPS]
        return sums

    @property
    def stick_slip(self) -> bool:
        """The stick-slip flag (model contract, section 7): a stick within the last
        ``stick_window``."""
        return bool(self._x[kn.X_SINCE_STICK] < self.stick_window)

    @property
    def hole_bottom(self) -> float:
        """Deepest point of the rock surface [L*], positive downhole."""
        return float(self._x[kn.X_HOLE])

    @property
    def surface(self) -> np.ndarray:
        """A copy of the rock surface S over one sector [L*], the current pass included."""
        return self._surf.copy()

    @property
    def surface_behind(self) -> float:
        """S at the last node the blades passed, from before the current pass [L*]: what the
        next depth of cut is measured against there (``load_state`` takes it back)."""
        return float(self._x[kn.X_S_BEHIND])

    def reset_window(self) -> None:
        """Start a new metrics window now."""
        self._acc[:] = 0.0
        self._acc[kn.A_OMEGA_MIN] = math.inf
        self._acc[kn.A_OMEGA_MAX] = -math.inf
        self._acc[kn.A_W] = -self.dt * self._x[kn.X_SUM_W]   # the pending sample's steps are
        self._acc[kn.A_T] = -self.dt * self._x[kn.X_SUM_T]   # before the window

    def window_metrics(self) -> Metrics:
        """Metrics (model contract, section 7) over the window since the last ``reset_window``."""
        acc = self._acc.copy()
        acc[kn.A_W] += self.dt * self._x[kn.X_SUM_W]
        acc[kn.A_T] += self.dt * self._x[kn.X_SUM_T]
        return Metrics.from_accumulators(acc)
