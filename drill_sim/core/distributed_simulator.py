"""``StringSimulator``: the ``Simulator`` API on a distributed string (dimensionless).

The BHA, the bit, the rock surface, the commands, the metrics window and the outputs are the
lumped simulator's (same state layout, same rows); the string is two sets of ring buffers
(torsional and axial invariants) advanced by ``distributed_kernel.advance``. ``ts`` (the
surface torque) is the torque at the top of the string; the pipe's torque on the BHA is
``bottom_torque``. Starts: ``start_steady`` (every section carrying the steady torque and force
at the steady speeds) and ``start_at_rest`` (string relaxed, hanging in static equilibrium).
"""

from __future__ import annotations

import math

import numpy as np

from . import distributed_kernel as dk
from . import state_layout as sl
from .distributed import StringWaves, WaveLine, geometry_waves
from .parameters import Groups, ParameterError, RigParameters, Scales, check_number
from .simulator import Simulator
from .string_geometry import StringGeometry
from .top_drive import DriveGroups


class LineArrays:
    """The arrays of one wave line: impedances, ring buffers (N + 1 slots per direction for a
    travel time of (N + f) steps), their offsets, the fractions f, dashpots, relative dashpots
    across the segments, the material low-passes' time constants and states (row 0: a, 1: b)."""

    def __init__(self, line: WaveLine) -> None:
        self.z = np.ascontiguousarray(line.z, dtype=np.float64)
        self.n = np.ascontiguousarray(line.steps + 1, dtype=np.int64)
        self.f = np.ascontiguousarray(line.frac, dtype=np.float64)
        self.c = np.ascontiguousarray(line.dashpot, dtype=np.float64)
        self.rel = np.ascontiguousarray(line.relative, dtype=np.float64)
        self.tau = np.ascontiguousarray(line.tau, dtype=np.float64)
        self.state = np.zeros((2, self.z.size))
        # the low-passes' trapezoidal step y+ = keep y + gain x, r = h/(2 tau); gain 0: none
        with np.errstate(divide="ignore"):
            r = np.where(self.tau > 0.0, 0.5 * line.h / np.where(self.tau > 0.0, self.tau, 1.0),
                         0.0)
        self.lowpass = np.ascontiguousarray(np.vstack([(1.0 - r) / (1.0 + r), 2.0 * r / (1.0 + r)]))
        self.off = np.concatenate([[0], np.cumsum(2 * self.n)[:-1]]).astype(np.int64)
        self.buf = np.zeros(int(2 * self.n.sum()))

    FIXED = ("z", "n", "f", "c", "rel", "off")        # what running does not change

    def kernel_args(self) -> tuple:
        """The line as ``distributed_kernel.advance`` takes it: (z, n, f, c, rel, off, buf,
        lowpass, state)."""
        return (self.z, self.n, self.f, self.c, self.rel, self.off, self.buf, self.lowpass,
                self.state)

    def fill_steady(self, force: float, speed: float, wall: np.ndarray | None = None) -> float:
        """Every segment carrying ``force`` at the BHA plus the dashpots below it, at
        ``speed``, and the wall's friction ``wall`` at each station (None: none); returns the
        force at the top."""
        extra = np.zeros(self.n.size) if wall is None else wall
        below = force + self.c[-1] * speed + extra[-1]
        for j in range(self.n.size - 1, -1, -1):
            o, m = self.off[j], self.n[j]
            self.buf[o:o + m] = below + self.z[j] * speed
            self.buf[o + m:o + 2 * m] = below - self.z[j] * speed
            self.state[:, j] = below + self.z[j] * speed, below - self.z[j] * speed
            if j > 0:
                below += self.c[j - 1] * speed + extra[j - 1]
        return below

    def energy(self, h: float, steps: int) -> float:
        """Energy in transit after ``steps`` steps: h (a^2 + b^2)/(4 z) of every departure still
        on its way, the oldest (slot ``steps`` mod (N + 1)) for the fraction f of it, plus what
        the material's low-passes hold, tau y^2/(4 z)."""
        total = 0.0
        for j in range(self.n.size):
            o, m = self.off[j], self.n[j]
            oldest = steps % m
            e = float(np.sum(self.buf[o:o + 2 * m] ** 2))
            e -= (1.0 - self.f[j]) * (self.buf[o + oldest] ** 2 + self.buf[o + m + oldest] ** 2)
            total += e / (4.0 * self.z[j])
        held = float(np.sum(self.tau * (self.state[0] ** 2 + self.state[1] ** 2) / (4.0 * self.z)))
        return h * total + held


def wall_columns(lines: tuple[LineArrays, LineArrays], static: np.ndarray) -> np.ndarray:
    """The junctions' inverse where the wall rubs (``distributed_kernel._junctions_wall``):
    for each line (torsional, axial) and rubbing station k, the speeds a unit force at k gives
    every station (A^-1 e_k, with A the junctions' tridiagonal system: the impedances, the
    dashpot, the relative dashpots on either side) then every rubbing station; then two rows:
    A's elimination factors by station (the upper factor, then after the stations each
    contact's resistance 1/(A^-1)_kk; 1/pivot). Shape (2, K + 2, M + K), M the stations.
    Fixed: A does not change with the state."""
    rub = np.flatnonzero(static[:-1] > 0.0)     # the last: the BHA's contact, not a station
    k, m = rub.size, lines[0].z.size - 1
    out = np.zeros((2, k + 2, m + k))
    for i, line in enumerate(lines):
        z, c, rel = line.z, line.c, line.rel
        a = np.diag(z[:-1] + z[1:] + c[:-1] + rel[:-1] + rel[1:])
        a -= np.diag(rel[1:-1], 1) + np.diag(rel[1:-1], -1)
        cols = np.linalg.solve(a, np.eye(m)[:, rub]).T
        out[i, :k, :m] = cols
        out[i, :k, m:] = cols[:, rub]
        upper = 0.0                              # the elimination's fixed factors
        for j in range(m):
            pivot = a[j, j] - rel[j] * upper     # rel[j]: the part above station j + 1
            upper = rel[j + 1] / pivot
            out[i, k, j], out[i, k + 1, j] = upper, 1.0 / pivot
        out[i, k, m:] = 1.0 / np.diag(cols[:, rub])     # each contact's resistance
    return out


class StringSimulator(Simulator):
    """The RGD bit on a distributed string. ``waves`` must be built at this step (waves.h);
    ``drive``: the top drive (default kinematic), whose inertia is the string's top boundary
    in speed and torque mode (``distributed_kernel``)."""

    MODEL = sl.DISTRIBUTED
    # the lines' waves and low-passes, the wall's contact forces (scratch) and held stations
    STATE_ARRAYS = (*Simulator.STATE_ARRAYS, "torsion.buf", "torsion.state", "axial.buf",
                    "axial.state", "scratch", "stuck")

    def __init__(self, groups: Groups, waves: StringWaves, *, stick_window: float = 4 * math.pi,
                 hoist_speed_limit: float = math.inf, nodes: int | None = None,
                 drive: DriveGroups | None = None) -> None:
        self.waves = waves
        self._t, self._a = LineArrays(waves.torsion), LineArrays(waves.axial)
        m = max(self._t.n.size, self._a.n.size)
        self._scratch = np.zeros((dk.NSCRATCH, m))
        self._slots = np.zeros((2, m), dtype=np.int64)
        wall = waves.wall                      # the wall's friction at the stations, or none
        self._wall = (np.zeros(0), np.zeros(0), np.zeros(0), 1.0, np.zeros((2, 0, 0))) \
            if wall is None else (
            np.ascontiguousarray(wall.static), np.ascontiguousarray(wall.dynamic),
            np.ascontiguousarray(wall.kappa), float(wall.sigma),
            wall_columns((self._t, self._a), wall.static))
        self._stuck = (self._wall[0] > 0.0).astype(np.int64)     # at rest: held
        super().__init__(groups, waves.h, stick_window=stick_window,
                         hoist_speed_limit=hoist_speed_limit, nodes=nodes, drive=drive)

    @classmethod
    def for_rig(cls, params: RigParameters, geometry: StringGeometry | None, dt: float,
                drive: DriveGroups) -> StringSimulator:
        """The distributed string of ``params`` and the pipe ``geometry`` at step ``dt`` [t*]."""
        if geometry is None:
            raise ParameterError("string_model = 'distributed' needs geometry: the preset's "
                                 "string (a StringGeometry); a preset with 'lumped' has none")
        return cls(params.groups, geometry_waves(params, geometry, dt), drive=drive)

    def carried_to(self, groups: Groups, dt: float, drive: DriveGroups, old: Scales,
                   new: Scales) -> Simulator:
        raise ParameterError("replace_parameters: not available with string_model = "
                             "'distributed' (its state is the pipe's wave buffers, which "
                             "cannot be carried to new parameters); make a new Rig")

    def _homes(self) -> dict[str, tuple[object, str]]:
        homes = super()._homes()
        for name, line in (("torsion", self._t), ("axial", self._a)):
            homes |= {f"{name}.{attr}": (line, attr) for attr in (*LineArrays.FIXED, "buf",
                                                                   "lowpass", "state")}
        return homes | {"scratch": (self, "_scratch"), "slots": (self, "_slots"),
                        "stuck": (self, "_stuck")}

    def kernel_args(self) -> tuple:
        """What ``distributed_kernel.advance`` takes after the lumped arrays: the torsional
        and the axial line, the wall's friction, the rig's work arrays."""
        return (self._t.kernel_args(), self._a.kernel_args(), self._wall,
                (self._scratch, self._slots, self._stuck))

    # ---- the hook ------------------------------------------------------------------------
    def set_hook(self, position: bool, block_speed: float = 0.0) -> None:
        """The string's axial top boundary: the hook's force (``position`` False: the hook
        holds w0, ``set_commands``) or the block's motion (True: the top moves at
        ``block_speed`` [L*/t*], positive down, 0 held, whatever force that takes)."""
        speed = check_number("block speed", block_speed, low=None)
        self._c[sl.C_HOOK_POSITION], self._c[sl.C_V_BLOCK] = float(bool(position)), speed

    def absorb_at_top(self, level: float | None, t_min: float = -math.inf,
                      t_max: float = math.inf) -> None:
        """The top reflecting nothing, the ideal of a top-end law that absorbs the string's
        waves (kinematic mode): the drive's motor turns its inertia so that the top sends down
        the torsional invariant ``level`` [C] (a = T + Z omega) whatever arrives (b), as a
        torque source behind the top section's own impedance Z would: the top turns at
        (level - b)/(2 Z), reached by each step's end (half a step late). The motor's torque
        is held within [``t_min``, ``t_max``] [C]; there the top reflects. Its mean speed is
        the caller's to hold, through ``level`` (the mean torque plus Z omega0 keeps omega0).
        None: the speed omega0 imposed again."""
        if level is None:
            self._c[sl.C_TOP_ABSORB] = 0.0
            return
        if self.drive.mode != "kinematic":
            raise ParameterError("absorb_at_top: expected the kinematic drive (the top's speed "
                                 f"is its own), not {self.drive.mode!r}")
        lo = -math.inf if t_min == -math.inf else check_number("t_min", t_min, low=None)
        hi = math.inf if t_max == math.inf else check_number(
            "t_max", t_max, low=None if lo == -math.inf else lo)
        self._c[sl.C_TOP_LEVEL] = check_number("level", level, low=None)
        self._c[sl.C_TOP_T_MIN], self._c[sl.C_TOP_T_MAX] = lo, hi
        self._c[sl.C_TOP_ABSORB] = 1.0

    @property
    def top_impedance(self) -> float:
        """The top section's torsional impedance Z [C t*]."""
        return float(self.waves.torsion.z[0])

    @property
    def hook_position(self) -> bool:
        """The block holds the top (True) or the hook's force does (False)."""
        return bool(self._c[sl.C_HOOK_POSITION])

    @property
    def top_force(self) -> float:
        """The force the string's top takes from the hook, counted as w0 is [F*]: the
        available weight; the hook carries W_s less it."""
        return float(self._x[sl.X_F_TOP])

    # ---- starts --------------------------------------------------------------------------
    def start_steady(self, w0: float, omega0: float, perturbation: float = 0.0) -> None:
        """Steady drilling everywhere: the string turns at omega0 carrying the steady torque
        (plus the dashpots' and the wall's sliding friction's share above each), moves at v0
        with the hook holding w0; the axial dashpots and the wall take their drag of it, so
        the bit drills steadily under w0 less that (``steady_state``); BHA speed perturbed.
        A top drive in the loop turns at omega0 under the torque at the top of the string (its
        motor torque, PI integral term and torque command)."""
        w_bit = self._bit_weight(w0, omega0)
        super().start_steady(w_bit, omega0, perturbation)
        self.set_commands(w0, omega0)          # the hook holds the available weight
        st = self.steady(w_bit, omega0)        # the bit's (``steady_state``)
        x = self._x
        wall_t, wall_a = self._wall_forces(st.v0, omega0)
        self._stuck[:] = 0                     # sliding everywhere
        self._scratch[:] = 0.0
        x[sl.X_TS] = self._t.fill_steady(st.t0, omega0, wall_t)
        d = self.drive
        if not d.holds(x[sl.X_TS]):
            raise ParameterError(f"steady drilling needs a motor torque of {x[sl.X_TS]:.4g} C, "
                                 f"outside the drive's limits [{d.t_min:.4g}, {d.t_max:.4g}] C")
        x[sl.X_TM] = x[sl.X_TREF] = x[sl.X_DRIVE_I] = self._c[sl.C_T_CMD] = x[sl.X_TS]
        x[sl.X_F_TOP] = self._a.fill_steady(w_bit, st.v0, wall_a)
        x[sl.X_PHI_TD] = self._twist(st.t0, omega0, wall_t)
        x[sl.X_T_BOTTOM], x[sl.X_F_BOTTOM], x[sl.X_V_TOP] = st.t0, w_bit, st.v0
        x[sl.X_DOM] = x[sl.X_DV] = 0.0
        x[sl.X_A_PREV] = self._t.buf[self._t.off[-1]]
        if wall_t is not None:                 # the BHA's contact, sliding
            x[sl.X_BHA_WALL_T], x[sl.X_BHA_WALL_F] = wall_t[-1], wall_a[-1]

    def _wall_forces(self, v: float, omega: float) -> tuple[np.ndarray | None, ...]:
        """The wall's sliding friction at each station (torque [C], force [F*]), or Nones."""
        if self.waves.wall is None:
            return None, None
        return self.waves.wall.forces(v, omega)

    def _bit_weight(self, w0: float, omega0: float) -> float:
        """The weight on bit of steady drilling under the hook's w0: w = w0 - sum(c_a) v0(w)
        - the wall's axial drag at v0(w), by fixed-point iteration (the drag's share is small:
        its derivative in w << 1)."""
        drag, w = float(np.sum(self._a.c)), w0
        if drag == 0.0 and self.waves.wall is None:
            return w
        for _ in range(100):
            v0 = self.steady(w, omega0).v0
            wall_a = self._wall_forces(v0, omega0)[1]
            w_new = w0 - drag * v0 - (0.0 if wall_a is None else float(np.sum(wall_a)))
            if abs(w_new - w) <= 1e-15 * abs(w0):
                break
            w = w_new
        return w

    def _twist(self, t0: float, omega0: float, wall: np.ndarray | None = None) -> float:
        """Twist of the steady string, top angle minus bit angle: sum of T_j D_j / z_j (the
        wall's friction ``wall`` at the stations, None: none)."""
        extra = np.zeros(self.waves.torsion.z.size) if wall is None else wall
        line = self.waves.torsion
        total, torque = 0.0, t0 + line_c_last(self.waves) * omega0 + extra[-1]
        for j in range(line.z.size - 1, -1, -1):
            total += torque * line.delay[j] / line.z[j]
            if j > 0:
                torque += line.dashpot[j - 1] * omega0 + extra[j - 1]
        return total

    @property
    def steady_state(self):
        """Steady drilling under the commands: at the bit, the hook's w0 less the axial
        dashpots' drag (``start_steady``)."""
        w0, om0 = self.commands
        return self.steady(self._bit_weight(w0, om0), om0)

    def start_at_rest(self, gap: float = 0.0) -> None:
        """Bit at rest ``gap`` [L*] above a flat bottom, string relaxed and hanging in static
        equilibrium (the hook carries the weight), commands zero."""
        super().start_at_rest(gap)
        for line in (self._t, self._a):
            line.buf[:] = 0.0
            line.state[:] = 0.0
        self._stuck[:] = self._wall[0] > 0.0    # at rest against the wall
        self._scratch[:] = 0.0

    def place(self, state: object, *, steps: int, surface: np.ndarray) -> None:
        raise ParameterError("place: a distributed string's state is its wave buffers, not a "
                             "physical placement; start it (start_steady, start_at_rest) or "
                             "load a saved state (save_state, load_state)")

    # ---- stepping ------------------------------------------------------------------------
    def advance_into(self, n_steps: int, out: np.ndarray, every: int, row: int) -> int:
        row = int(dk.advance(self._x, self._k, self._surf, self._p, self._c, self._acc,
                             *self.kernel_args(), n_steps, out, every, row))
        if self._k[sl.K_REFUSED]:
            self._refuse_step()
        return row

    def advance(self, n_steps: int) -> None:
        self.advance_into(n_steps, self._no_rows, 1, 0)

    def record(self, duration: float, output_interval: float) -> np.ndarray:
        """Rows (kernel.O_* then distributed_kernel.O_T_BOTTOM..) every ``output_interval``."""
        n_total = round(duration / self.dt)
        every = max(1, round(output_interval / self.dt))
        out = np.empty((n_total // every, sl.NOD))
        self.start_sample()
        row = self.advance_into(n_total, out, every, 0)
        return out[:row]

    # ---- observation ---------------------------------------------------------------------
    @property
    def bottom_torque(self) -> float:
        """The pipe's torque on the BHA over the last step [C]."""
        return float(self._x[sl.X_T_BOTTOM])

    def energy(self) -> tuple[float, float]:
        """Stored energy (torsional [C], axial [F* L*]): string waves plus the BHA's kinetic
        energy (I = 1; M = 1/psi in these units) plus, with a top drive in the loop, the
        drive's, j Omega_TD^2 / 2 (and with the top absorbing, ``absorb_at_top``)."""
        x = self._x
        turns = self.drive.mode != "kinematic" or self._c[sl.C_TOP_ABSORB] != 0.0
        drive = 0.5 * self.drive.j * x[sl.X_OMEGA_TD] ** 2 if turns else 0.0
        return (self._t.energy(self.dt, self.steps) + 0.5 * x[sl.X_OMEGA] ** 2 + drive,
                self._a.energy(self.dt, self.steps) + 0.5 * x[sl.X_V] ** 2 / self.groups.psi)

    def damped(self) -> tuple[float, float]:
        """Energy the pipe's damping (dashpots, viscous and material) dissipated over the
        window (torsional [C], axial [F* L*])."""
        return float(self._acc[sl.A_DAMPED_ROT]), float(self._acc[sl.A_DAMPED_AX])

    def wall_friction(self) -> tuple[float, float]:
        """Energy the wall's friction dissipated over the window (torsional [C], axial
        [F* L*])."""
        return float(self._acc[sl.A_WALL_ROT]), float(self._acc[sl.A_WALL_AX])

    @property
    def wall_held(self) -> np.ndarray:
        """Which stations the wall holds at rest (1) or the pipe slides past (0), aligned with
        the segments (``WallFriction``; empty without one)."""
        return self._stuck.copy()

    def transport_loss(self) -> tuple[float, float]:
        """Energy the transport's weighting of two departures (a fractional travel time)
        dissipated over the window (torsional [C], axial [F* L*]): second order in h for
        smooth waves, O(h) per passage of a jump (a stick, a landing)."""
        return float(self._acc[sl.A_LOSS_ROT]), float(self._acc[sl.A_LOSS_AX])


def line_c_last(waves: StringWaves) -> float:
    """The torsional dashpot acting on the BHA (the last segment's)."""
    return float(waves.torsion.dashpot[-1])
