"""The dimensionless stepper: fixed-size state, commands held between calls, window metrics.

``Simulator`` owns the state arrays of the kernel and is what the ROS node advances every tick.
``Simulator.run`` is the offline driver, returning a ``Trajectory`` with named columns.
All quantities here are dimensionless (model contract, section 3); ``drill_sim.core.rig``
converts.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from . import kernel as kn
from . import state_layout as sl
from .metrics import Metrics
from .parameters import Groups, ParameterError, RigParameters, Scales, check_number
from .resolution import (
    MAX_NODES,
    STEPS_PER_PERIOD,
    fastest_period,
    max_step,
    resolves,
    surface_nodes,
)
from .rig_step import take_force_sums
from .stability import SteadyState, steady_state
from .string_geometry import StringGeometry
from .top_drive import DriveGroups
from .trajectory import VIEW_SLOTS, StateView, Trajectory

DEFAULT_DT = 5e-4            # [t*]; halving it moves stationary metrics ~2e-5 (test_validation)


@dataclass(frozen=True)
class SavedState:
    """A simulator's whole state (``Simulator.save_state``): its string model and copies of
    its state arrays by name."""

    model: str
    arrays: dict[str, np.ndarray]


class Simulator:
    """Fixed-step integration of the RGD model in dimensionless form, on the lumped string.

    dt: step [t*]. stick_window: how long the stick-slip flag stays up after a stick [t*];
    default two torsional periods (4 pi). hoist_speed_limit: the string rises no faster [L*/t*].
    drive: the top drive (default kinematic: the seed's ideal speed source).

    A string model is a subclass (``distributed_simulator.StringSimulator``) and provides:

    - ``MODEL``: its name, which says the slots of ``state_layout`` its arrays hold (every
      array is sized for it at construction), and ``for_rig``, its simulator of SI
      parameters and a pipe;
    - its own arrays, named in ``_homes`` (``arrays``), those that hold state in
      ``STATE_ARRAYS`` (``save_state``/``load_state`` keep them exactly; the vector
      environment stacks every one a rig owns);
    - ``advance_into``, its kernel: the bit, the rock and the window's integrals as the lumped
      kernel keeps them (``kernel._accumulate``, the same rows), the string its own;
    - ``start_steady`` and ``start_at_rest`` that leave every one of its arrays started;
    - at the top of the string: ``set_hook``/``hook_position`` if its top can be moved by the
      block, ``top_force`` if its top carries a force of its own (else None: the command);
    - ``carried_to``: the same physical state under new parameters, or ParameterError if its
      state cannot be carried.
    """

    MODEL = sl.LUMPED       # the string model: which slots of ``state_layout`` it holds

    @classmethod
    def for_rig(cls, params: RigParameters, geometry: StringGeometry | None, dt: float,
                drive: DriveGroups) -> Simulator:
        """The simulator of SI ``params`` (their groups) at step ``dt`` [t*]; the lumped string
        has no pipe of its own (``geometry`` unused)."""
        return cls(params.groups, dt, drive=drive)

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
        self._p = sl.PARAMETERS.empty(self.MODEL)
        self._p[:sl.P_MODE] = (groups.n, groups.psi, groups.lam, groups.beta, self.dt, dtheta,
                               1.0 / dtheta)
        self.rock = (1.0, groups.lam, groups.beta)   # set_rock
        self._x = sl.STATE.empty(self.MODEL)
        self._k = sl.COUNTS.empty(self.MODEL)
        self._surf = np.zeros(nodes)
        self._c = sl.COMMANDS.empty(self.MODEL)
        self._acc = sl.WINDOW.empty(self.MODEL)
        self._no_rows = np.zeros((0, sl.OUTPUTS.size(self.MODEL)))
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
        dtheta = self._p[sl.P_DTHETA]
        theta = np.arange(nodes) * dtheta
        self._surf[:] = st.v0 * (theta - 2.0 * math.pi / self.groups.n) / st.omega0
        self._surf[0] = 0.0
        self._x[:] = 0.0                       # X_HOLE = 0: the deepest point is under the bit
        self._x[sl.X_V] = st.v0
        self._x[sl.X_OMEGA] = st.omega0 * (1.0 + perturbation)
        self._x[sl.X_PHI_TD] = st.t0
        self._x[sl.X_S_BEHIND] = -st.delta_n0
        self._x[sl.X_SINCE_STICK] = math.inf
        self._x[sl.X_W] = w0
        self._x[sl.X_T] = self._x[sl.X_TS] = st.t0
        self._x[sl.X_DELTA] = st.delta_n0
        self._x[sl.X_G] = 1.0
        x = self._x      # the drive turns at omega0 under the steady torque; the PI's error is 0
        x[sl.X_OMEGA_TD] = omega0
        x[sl.X_TM] = x[sl.X_TREF] = x[sl.X_DRIVE_I] = st.t0
        self._c[sl.C_T_CMD] = st.t0
        self._k[:] = 0
        self._k[sl.K_REGIME] = kn.REGIME_ROTATING
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
        self._p[sl.P_N] = self.groups.n * cutting
        self._p[sl.P_LAM], self._p[sl.P_BETA] = lam, beta

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
        self._c[sl.C_T_CMD] = 0.0
        self._surf[:] = 0.0
        self._x[:] = 0.0
        self._x[sl.X_U] = -gap
        self._x[sl.X_SINCE_STICK] = math.inf
        self._k[:] = 0
        self._k[sl.K_REGIME] = kn.REGIME_OFF_BOTTOM if gap > 0.0 else kn.REGIME_STUCK
        self.reset_window()

    def place(self, state: StateView, *, steps: int, surface: np.ndarray) -> None:
        """Put the bit, string and rock in a given physical state (dimensionless), the
        commands, parameters and metrics window kept: the lumped string's placement (a
        distributed string's state is its wave buffers: ``save_state``/``load_state``).

        ``state`` holds the slots of ``StateView`` (``dataclasses.replace`` of a ``state()``
        sets some); ``steps`` the step count it is at. ``surface`` is S over one sector at any
        even spacing (node 0 at the sector's start), as ``surface`` reads it, resampled onto
        this simulator's nodes. The blades' current pass has already cut the last node they
        passed (the node at or below phi); its value from before the pass, which the next
        depth of cut is measured against, is ``state.surface_behind``. w, t, delta_n and g
        are what the last step's outputs read until the next step; the force sums of the next
        sample start from here. ts is phi_td - phi and the hole's bottom the surface's
        deepest point, whatever ``state`` says; kinematic mode keeps the top drive at the
        speed command.
        """
        values = np.array([getattr(state, name) for name, _ in VIEW_SLOTS], dtype=float)
        if not np.all(np.isfinite(values[[i for i, (name, _) in enumerate(VIEW_SLOTS)
                                          if name != "since_stick"]])) \
                or not np.all(np.isfinite(surface)):
            raise ParameterError("place: the state must be finite")
        self.take_force_sums()            # the window keeps the steps before the placement
        src = np.asarray(surface, dtype=float)
        before = src.copy()               # the surface as the current pass found it
        phi = float(state.phi)
        before[math.floor(phi * src.size * self.groups.n / (2.0 * math.pi)) % src.size] = \
            state.surface_behind
        nodes = self._surf.size
        x_src = np.arange(src.size + 1) / src.size
        x_dst = np.arange(nodes) / nodes
        self._surf[:] = np.interp(x_dst, x_src, np.append(src, src[0]))
        k_last = math.floor(phi * self._p[sl.P_INV_DTHETA])
        k_node = k_last & (nodes - 1)
        x = self._x
        for (_, i), value in zip(VIEW_SLOTS, values, strict=True):
            x[i] = value
        x[sl.X_HOLE] = float(self._surf.max())
        x[sl.X_TS] = state.phi_td - state.phi
        x[sl.X_S_BEHIND] = float(np.interp(x_dst[k_node], x_src, np.append(before, before[0])))
        x[sl.X_SUM_W] = x[sl.X_SUM_T] = 0.0
        if self.drive.mode == "kinematic":
            x[sl.X_OMEGA_TD] = self._c[sl.C_OMEGA0]
        k = self._k
        k[:] = 0
        k[sl.K_LAST], k[sl.K_REGIME], k[sl.K_STEPS], k[sl.K_SAMPLED] = (k_last, state.regime,
                                                                      steps, steps)

    def _homes(self) -> dict[str, tuple[object, str]]:
        """Every array this simulator steps, by name: (the object holding it, its attribute).
        The lumped string's: the state x, k, the rock surface, the commands, the window's
        integrals and the parameters p; a string model adds its own."""
        return {"x": (self, "_x"), "k": (self, "_k"), "surface": (self, "_surf"),
                "c": (self, "_c"), "acc": (self, "_acc"), "p": (self, "_p")}

    STATE_ARRAYS: tuple[str, ...] = ("x", "k", "surface", "c", "acc")   # what save_state keeps

    def arrays(self) -> dict[str, np.ndarray]:
        """Every array this simulator steps, by name (``_homes``), not copies."""
        return {name: getattr(owner, attr) for name, (owner, attr) in self._homes().items()}

    def save_state(self) -> SavedState:
        """A copy of the whole state (``STATE_ARRAYS``: the kernels' state, counts, rock
        surface, held commands and window integrals; a string model's own arrays too), to
        ``load_state`` later; the parameters (the rock being cut, the drive) are not state."""
        arrays = self.arrays()
        return SavedState(self.MODEL, {name: arrays[name].copy() for name in self.STATE_ARRAYS})

    def load_state(self, saved: SavedState) -> None:
        """Back to a ``save_state`` of a simulator of this model and shape, exactly; the
        parameters stay this simulator's. Refused, nothing changed, for another model or
        shape."""
        arrays = self.arrays()
        if saved.model != self.MODEL or set(saved.arrays) != set(self.STATE_ARRAYS) or any(
                saved.arrays[n].shape != arrays[n].shape for n in self.STATE_ARRAYS):
            raise ParameterError(f"load_state: a saved {saved.model} state of another shape "
                                 f"than this {self.MODEL} simulator's (string model, step or "
                                 "string): expected one saved from a simulator like this one")
        for name in self.STATE_ARRAYS:
            np.copyto(arrays[name], saved.arrays[name])

    # ---- commands -----------------------------------------------------------------------
    def set_commands(self, w0: float, omega0: float) -> None:
        """Available weight w0 = W0/F* (any sign) and top-drive speed omega0 >= 0, held from now.

        A speed that would turn the bit more than a sector 2 pi/n in one step is refused."""
        w0 = check_number("w0", w0, low=None)
        omega0 = check_number("omega0", omega0, low_inclusive=True,
                              high=2.0 * math.pi / self.groups.n / self.dt)
        self._c[sl.C_W0], self._c[sl.C_OMEGA0] = w0, omega0   # both valid, or neither set
        if self.drive.mode == "kinematic":
            self._x[sl.X_OMEGA_TD] = omega0

    def set_motor_torque(self, torque: float) -> None:
        """The motor torque command [C] (torque mode), held from now; the drive's limits, rate
        limit and lag act on it."""
        self._c[sl.C_T_CMD] = check_number("motor torque", torque, low=None)

    @property
    def motor_torque_command(self) -> float:
        return float(self._c[sl.C_T_CMD])

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
                x[sl.X_OMEGA_TD] = c[sl.C_OMEGA0]
                x[sl.X_TM] = x[sl.X_TREF] = x[sl.X_TS]
            if drive.mode == "torque":
                c[sl.C_T_CMD] = x[sl.X_TM]
            elif drive.mode == "speed":
                error = c[sl.C_OMEGA0] - x[sl.X_OMEGA_TD]
                x[sl.X_DRIVE_I] = min(max(x[sl.X_TREF] - drive.kp * error, drive.t_min),
                                      drive.t_max)
            else:
                x[sl.X_OMEGA_TD] = c[sl.C_OMEGA0]
        self.drive = drive
        self._write_drive(drive)

    def _write_drive(self, d: DriveGroups) -> None:
        self._advance = kn.stepper(d.code)
        p = self._p
        p[sl.P_MODE], p[sl.P_J], p[sl.P_T_MAX], p[sl.P_T_MIN] = d.code, d.j, d.t_max, d.t_min
        p[sl.P_RATE], p[sl.P_LAG], p[sl.P_KP], p[sl.P_KI] = d.rate, d.lag, d.kp, d.ki
        p[sl.P_LAG_END], p[sl.P_LAG_MEAN] = d.lag_weights(self.dt)

    def set_hoist_speed_limit(self, limit: float) -> None:
        """Fastest upward axial speed [L*/t*]; math.inf for none (the pure model)."""
        if limit != math.inf:
            limit = check_number("hoist_speed_limit", limit)
        self._c[sl.C_V_MIN] = -limit

    @property
    def commands(self) -> tuple[float, float]:
        return float(self._c[sl.C_W0]), float(self._c[sl.C_OMEGA0])

    # ---- the top of the string ----------------------------------------------------------
    hook_position = False     # the block holds the top (a string model whose top can move)

    def set_hook(self, position: bool, block_speed: float = 0.0) -> None:
        """The string's axial top boundary: the hook's force (``position`` False, the only one
        of a lumped string: it is axially rigid, so a held block would hold the bit)."""
        if position:
            raise ParameterError("hook_mode = 'position' needs string_model = 'distributed': "
                                 "the lumped string is axially rigid, so a block held still "
                                 "would hold the bit; use hook_mode = 'force'")

    @property
    def top_force(self) -> float | None:
        """The force the string's top takes from the hook [F*]; None: the lumped string has
        none of its own (the command w0)."""
        return None

    def carried_to(self, groups: Groups, dt: float, drive: DriveGroups, old: Scales,
                   new: Scales) -> Simulator:
        """A simulator of ``groups`` at step ``dt`` [t*] with ``drive``, in the physical state
        of this one (``place``: every slot carried from the ``old`` scales to the ``new``), at
        this one's step count."""
        sim = type(self)(groups, dt, drive=drive)
        sim.place(self.state().rescaled(old, new), steps=self.steps,
                  surface=sl.LENGTH.rescale(self.surface, old, new))
        return sim

    # ---- stepping -----------------------------------------------------------------------
    def advance(self, n_steps: int) -> None:
        """Advance ``n_steps`` steps with the commands held; allocation-free.

        Raises ParameterError, the state left after the last step taken, before a step that
        would turn the bit more than a sector (see ``kernel.advance``)."""
        self._advance(self._x, self._k, self._surf, self._p, self._c, self._acc, n_steps,
                      self._no_rows, 1, 0)
        if self._k[sl.K_REFUSED]:
            self._refuse_step()

    def _refuse_step(self) -> None:
        sector = 2.0 * math.pi / self.groups.n
        raise ParameterError(
            f"at tau = {self.tau:.6g} the next step (dt = {self.dt:g}) would turn the bit more "
            f"than a sector 2 pi/n = {sector:.4g} rad, from bit speed {self._x[sl.X_OMEGA]:.4g}: "
            "the rock surface cannot be swept nor the depth of cut measured; use a smaller dt "
            "or less weight on bit (the string winds up to about w0, and the bit slips at "
            "about that speed); the state is kept at the last step")

    def advance_into(self, n_steps: int, out: np.ndarray, every: int, row: int) -> int:
        """Advance and write a row to ``out`` at every step count that is a multiple of ``every``;
        return the next free row. A row is a sample: its w and t are the means over the steps
        since the previous sample (a row, ``take_force_sums``, ``start_sample``, a start)."""
        row = int(self._advance(self._x, self._k, self._surf, self._p, self._c, self._acc,
                                n_steps, out, every, row))
        if self._k[sl.K_REFUSED]:
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
            out = np.empty((n_total // every + 1, sl.NO))
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
        return float(self._x[sl.X_TAU])

    @property
    def steps(self) -> int:
        return int(self._k[sl.K_STEPS])

    @property
    def regime(self) -> int:
        """kernel.REGIME_* of the last step."""
        return int(self._k[sl.K_REGIME])

    @property
    def counts(self) -> np.ndarray:
        """The kernel's integer state itself (indexed by ``state_layout.K_*``), not a copy.
        Read it; never write it."""
        return self._k

    @property
    def live_state(self) -> np.ndarray:
        """The kernel's state vector itself (indexed by kernel.X_*), not a copy: the cheapest
        read for a caller sampling every tick. Read it; never write it."""
        return self._x

    def state(self) -> StateView:
        """A copy of the physical state now (``StateView``; kinematic mode: the motor torque
        is the string's, ts)."""
        x = self._x
        values = {name: x[i] for name, i in VIEW_SLOTS}
        if self.drive.mode == "kinematic":
            values["motor_torque"] = x[sl.X_TS]
        return StateView(**values, regime=int(self._k[sl.K_REGIME]))

    def take_force_sums(self) -> tuple[float, float, int]:
        """(sum of w, sum of t, steps) over the steps since the previous sample (a call, an
        output row, a start or ``load_state``), and start the next: a sample's mean WOB and TOB
        are the sums over the steps (see ``Rig.sample``)."""
        sum_w, sum_t, n = take_force_sums(self._x, self._k, self._acc, self.dt)
        return float(sum_w), float(sum_t), int(n)

    @property
    def stick_slip(self) -> bool:
        """The stick-slip flag (model contract, section 7): a stick within the last
        ``stick_window``."""
        return bool(self._x[sl.X_SINCE_STICK] < self.stick_window)

    @property
    def hole_bottom(self) -> float:
        """Deepest point of the rock surface [L*], positive downhole."""
        return float(self._x[sl.X_HOLE])

    @property
    def surface(self) -> np.ndarray:
        """A copy of the rock surface S over one sector [L*], the current pass included."""
        return self._surf.copy()

    @property
    def surface_behind(self) -> float:
        """S at the last node the blades passed, from before the current pass [L*]: what the
        next depth of cut is measured against there (``load_state`` takes it back)."""
        return float(self._x[sl.X_S_BEHIND])

    def reset_window(self) -> None:
        """Start a new metrics window now."""
        self._acc[:] = 0.0
        self._acc[sl.A_OMEGA_MIN] = math.inf
        self._acc[sl.A_OMEGA_MAX] = -math.inf
        self._acc[sl.A_W] = -self.dt * self._x[sl.X_SUM_W]   # the pending sample's steps are
        self._acc[sl.A_T] = -self.dt * self._x[sl.X_SUM_T]   # before the window

    def window_metrics(self) -> Metrics:
        """Metrics (model contract, section 7) over the window since the last ``reset_window``."""
        acc = self._acc.copy()
        acc[sl.A_W] += self.dt * self._x[sl.X_SUM_W]
        acc[sl.A_T] += self.dt * self._x[sl.X_SUM_T]
        return Metrics.from_accumulators(acc)
