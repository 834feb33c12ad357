"""The SI face of the core: surface commands in SI, rig outputs in SI, time in seconds.

``Rig`` wraps a dimensionless ``Simulator`` and converts at the boundary, so the node, the CLI
and the recorder never see a dimensionless number.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import replace

import numpy as np

from . import state_layout as sl
from .distributed import check_string_model
from .distributed_simulator import StringSimulator
from .parameters import ParameterError, RigParameters, check_number, friction_torque_ratio
from .resolution import STEPS_PER_PERIOD, fastest_period, max_step, resolves
from .rig_sample import REGIME_OFF_BOTTOM, REGIME_STUCK, RigSample
from .rig_step import NR, R_MOTOR, mean_forces, sample_into, scale_row, surface_commands
from .simulator import DEFAULT_DT, Simulator
from .stability import NoSteadyDrilling, SteadyState
from .string_geometry import StringGeometry
from .top_drive import DriveGroups, TopDriveParameters
from .well import ROCK

# the string models' simulators, by name (``Simulator``'s contract)
SIMULATORS: dict[str, type[Simulator]] = {cls.MODEL: cls for cls in (Simulator, StringSimulator)}


def _check_step(dt_s: float, params: RigParameters, top_drive: TopDriveParameters) -> None:
    """Refuse a step that cannot resolve the fastest mode of these parameters, in SI."""
    drive = top_drive.groups(params.scales, params.bha_inertia_kg_m2)
    if not resolves(params.groups, drive, dt_s / params.scales.time_s):
        limit_s = max_step(params.groups, drive) * params.scales.time_s
        period_s = fastest_period(params.groups, drive) * params.scales.time_s
        raise ParameterError(
            f"dt_s = {dt_s:g} s cannot resolve the fastest mode of these parameters (period "
            f"{period_s:.4g} s): expected dt_s <= {limit_s:.4g} s, {STEPS_PER_PERIOD} steps a "
            "period")


class Rig:
    """A drilling rig in SI: ``command`` it, ``advance_to`` a time, ``sample`` its outputs.

    dt_s: fixed step [s] (default DEFAULT_DT t*); stick_window_s: how long the stick-slip flag
    stays up after a stick [s] (default two torsional periods, 4 pi t*); hoist_speed_limit_m_s:
    the string rises no faster (default unlimited); top_drive: the drive (default kinematic,
    the seed's ideal speed source; ``set_top_drive`` changes it at run time). string_model:
    ``lumped`` (default) or ``distributed`` (a ``StringSimulator`` of ``geometry``, the
    preset's ``string``, at the same step, any top drive: in speed and torque mode its inertia
    is the string's top boundary; the SI face is the same, but ``replace_parameters`` is
    refused).
    """

    def __init__(self, params: RigParameters, dt_s: float | None = None, *,
                 stick_window_s: float | None = None,
                 hoist_speed_limit_m_s: float = math.inf,
                 top_drive: TopDriveParameters | None = None, string_model: str = "lumped",
                 geometry: StringGeometry | None = None) -> None:
        self.params = params
        self.string_model = check_string_model(string_model)
        self.scales = params.scales
        self.groups = params.groups
        self.top_drive = TopDriveParameters() if top_drive is None else top_drive
        ts = self.scales.time_s
        dt = DEFAULT_DT if dt_s is None else check_number("dt_s", dt_s) / ts
        _check_step(dt * ts, params, self.top_drive)
        self.sim = self._simulator(dt, geometry)
        self._scale_row = scale_row(params, self.dt_s)     # the SI arithmetic's (rig_step)
        self._sample_row = np.zeros(NR)
        self.geometry = geometry               # the pipe of the distributed string
        self._torque_nm = 0.0
        self.set_stick_window(4.0 * math.pi * ts if stick_window_s is None else stick_window_s)
        self.set_hoist_speed_limit(hoist_speed_limit_m_s)
        self._hook_load_n = params.submerged_weight_n
        self._speed_rad_s = 0.0
        self.hook_mode, self.block_speed_m_s = "force", 0.0
        # the formations along the hole: their tops [m MD] and what each changes
        well = None if geometry is None else geometry.well
        self.formations = () if well is None else well.formations
        self._tops = [f.top_m for f in self.formations]
        self._start_md_m = 0.0 if geometry is None else geometry.length_m
        self.layer = -1                        # the formation the bit is in (-1: above them)
        self.rock = self._params_rock(params)
        self._forget_samples()

    def _simulator(self, dt: float, geometry: StringGeometry | None) -> Simulator:
        """The string model's simulator (``SIMULATORS``) of these parameters and pipe."""
        return SIMULATORS[self.string_model].for_rig(
            self.params, geometry, dt, self._drive_groups(self.params, self.top_drive))

    # ---- conversions --------------------------------------------------------------------
    @property
    def dt_s(self) -> float:
        return self.sim.dt * self.scales.time_s

    def w0_of(self, hook_load_n: float) -> float:
        """The available weight w0 [F*] of a hook load [N]."""
        return surface_commands(0.0, hook_load_n, self._scale_row)[0]

    def omega0_of(self, speed_rad_s: float) -> float:
        """The speed command omega0 [1/t*] of a top-drive speed [rad/s]."""
        return surface_commands(speed_rad_s, 0.0, self._scale_row)[1]

    @staticmethod
    def _drive_groups(params: RigParameters, top_drive: TopDriveParameters) -> DriveGroups:
        return top_drive.groups(params.scales, params.bha_inertia_kg_m2)

    def set_top_drive(self, top_drive: TopDriveParameters) -> None:
        """Change the top drive at run time (mode, inertia, limits, rate limit, lag, gains), the
        state kept; a change of mode is bumpless (``Simulator.set_drive``). Refused, nothing
        changed, if the step cannot resolve it."""
        _check_step(self.dt_s, self.params, top_drive)
        self.sim.set_drive(self._drive_groups(self.params, top_drive))
        self.top_drive = top_drive
        self._torque_nm = self.sim.motor_torque_command * self.scales.stiffness_nm_per_rad

    def set_top_drive_mode(self, mode: str) -> None:
        """``kinematic``, ``speed`` or ``torque``, the drive's other settings kept."""
        self.set_top_drive(replace(self.top_drive, top_drive_mode=mode))

    def set_hoist_speed_limit(self, limit_m_s: float) -> None:
        """The string rises no faster than this [m/s]; math.inf for no limit."""
        if limit_m_s != math.inf:
            limit_m_s = check_number("hoist_speed_limit_m_s", limit_m_s)
        self.hoist_speed_limit_m_s = limit_m_s
        self.sim.set_hoist_speed_limit(limit_m_s / self.scales.velocity_m_s)

    # ---- the rock: formations along the hole ---------------------------------------------
    @staticmethod
    def _params_rock(params: RigParameters) -> dict[str, float]:
        return {name: float(getattr(params, name)) for name in ROCK}

    def _cut(self, rock: dict[str, float]) -> None:
        """Cut ``rock`` (the ``ROCK`` values, SI) from now on, in the rig's scales."""
        p = self.params
        self.rock = dict(rock)
        self.sim.set_rock(
            rock["intrinsic_specific_energy_pa"] / p.intrinsic_specific_energy_pa,
            p.bit_radius_m * p.wear_flat_length_m * rock["contact_stress_pa"]
            / self.scales.force_n,
            friction_torque_ratio(rock["friction_coefficient"], p.wear_flat_orientation,
                                  p.cutting_inclination))

    @property
    def bit_measured_depth_m(self) -> float:
        """The bit's measured depth [m]: the string's length at the start plus its advance."""
        return self._start_md_m + float(self.sim.live_state[sl.X_U]) * self.scales.length_m

    def _follow_formations(self, start_md_m: float | None = None) -> bool:
        """Enter the formation the bit is in, if it changed; True if it did. Deeper, each
        formation crossed changes what it gives, in order, and a run-time change of the rock
        (``replace_parameters``) holds until a formation gives that value; at a start, or
        higher up, the rock is rebuilt from the parameters' down to the bit's formation.
        ``start_md_m``: a start, the bit drilling (or about to) at that measured depth [m]."""
        if not self._tops:
            return False
        start = start_md_m is not None
        md = start_md_m if start else self.bit_measured_depth_m
        layer = bisect_right(self._tops, md) - 1
        if layer == self.layer and not start:
            return False
        if start or layer < self.layer:        # from the parameters' rock down to the bit
            rock, crossed = self._params_rock(self.params), self.formations[:layer + 1]
        else:                                  # deeper: the layers crossed, in order
            rock, crossed = dict(self.rock), self.formations[self.layer + 1:layer + 1]
        for f in crossed:
            rock.update(f.changes())
        self.layer = layer
        self._cut(rock)
        return True

    # ---- the hook: force or position -------------------------------------------------------
    HOOK_MODES = ("force", "position")

    def set_hook_mode(self, mode: str, block_speed_m_s: float = 0.0) -> None:
        """The string's axial top boundary. ``force`` (default): the hook holds the commanded
        hook load. ``position``: the drawworks moves the block at ``block_speed_m_s`` [m/s],
        positive down (0: the block held), and the hook load is what the string's top then
        takes (``sample().hook_load_n``); hook-load commands are kept but not applied until
        the mode is ``force`` again, which starts bumplessly from the load measured then. Only
        the distributed string: the lumped one is axially rigid, so a held block would hold the
        bit."""
        if mode not in self.HOOK_MODES:
            raise ParameterError(f"hook_mode = {mode!r}: expected one of "
                                 f"{', '.join(self.HOOK_MODES)}")
        speed = check_number("block_speed_m_s", block_speed_m_s, low=-10.0, high=10.0)
        sim = self.sim
        if mode == "force" and sim.hook_position:    # bumpless: hold what the hook carries
            self._hook_load_n = self.measured_hook_load_n
            sim.set_commands(self.w0_of(self._hook_load_n), sim.commands[1])
        sim.set_hook(mode == "position", speed / self.scales.velocity_m_s)
        self.hook_mode, self.block_speed_m_s = mode, speed

    @property
    def measured_hook_load_n(self) -> float:
        """The hook load the string's top takes now [N]: W_s less the top's force. With the
        hook in force mode this is the commanded load (except while the hoisting speed limit
        holds the string); the lumped string has no top force of its own: the command."""
        top = self.sim.top_force
        if top is None:
            return self._hook_load_n
        return self.params.submerged_weight_n - top * self.scales.force_n

    def set_stick_window(self, window_s: float) -> None:
        """How long the stick-slip flag stays up after the bit was last stuck [s]."""
        self.stick_window_s = check_number("stick_window_s", window_s)
        self.sim.stick_window = self.stick_window_s / self.scales.time_s

    def replace_parameters(self, params: RigParameters) -> None:
        """Swap in new SI parameters at run time, keeping the physical state: bit position,
        speeds, string twist, the rock surface and the clock. The blade count cannot change
        (the surface's sector would), so that needs a new Rig."""
        if params.blade_count != self.params.blade_count:
            raise ParameterError(f"blade_count cannot change while running "
                                 f"({self.params.blade_count} -> {params.blade_count}): "
                                 "it changes the rock surface's sector; reset instead")
        _check_step(self.dt_s, params, self.top_drive)
        old, new = self.scales, params.scales
        sim = self.sim.carried_to(params.groups, self.dt_s / new.time_s,
                                  self._drive_groups(params, self.top_drive), old, new)
        sum_w, sum_t, n = self.sim.take_force_sums()     # carried over in SI to the next sample
        self._pending = (self._pending[0] + sum_w * old.force_n,
                         self._pending[1] + sum_t * old.stiffness_nm_per_rad, self._pending[2] + n)
        # the rock: a value changed now holds until a formation gives it; the others stay
        rock = {n: float(getattr(params, n)) if getattr(params, n) != getattr(self.params, n)
                else self.rock[n] for n in ROCK}
        self.params, self.scales, self.groups, self.sim = params, new, params.groups, sim
        self._scale_row = scale_row(params, self.dt_s)
        self._cut(rock)
        self.set_stick_window(self.stick_window_s)
        self.set_hoist_speed_limit(self.hoist_speed_limit_m_s)
        self.command(self._speed_rad_s, self._hook_load_n)
        self.command_motor_torque(self._torque_nm)

    # ---- commands and initial states ----------------------------------------------------
    def command(self, top_drive_speed_rad_s: float, hook_load_n: float) -> None:
        """Hold these surface commands from now on: top-drive speed >= 0, hook load >= 0."""
        speed = check_number("top_drive_speed_rad_s", top_drive_speed_rad_s, low_inclusive=True)
        hook = check_number("hook_load_n", hook_load_n, low_inclusive=True)
        self.sim.set_commands(*surface_commands(speed, hook, self._scale_row))
        self._speed_rad_s, self._hook_load_n = speed, hook

    def command_motor_torque(self, torque_nm: float) -> None:
        """Hold this motor torque command from now on [N m] (torque mode; the drive's limits,
        rate limit and lag act on it)."""
        torque_nm = check_number("motor_torque_nm", torque_nm, low=None)
        self.sim.set_motor_torque(torque_nm / self.scales.stiffness_nm_per_rad)
        self._torque_nm = torque_nm

    @property
    def commanded_motor_torque_nm(self) -> float:
        return self._torque_nm

    @property
    def motor_torque_nm(self) -> float:
        """The motor torque applied now [N m], as ``sample`` gives it (kinematic mode: the
        string torque), without taking ``sample``'s force means."""
        sim = self.sim
        sample_into(sim.live_state, sim.counts, sim.drive.mode == "kinematic", self._speed_rad_s,
                    self._scale_row, self._sample_row)
        return float(self._sample_row[R_MOTOR])

    @property
    def commanded_speed_rad_s(self) -> float:
        return self._speed_rad_s

    @property
    def commanded_hook_load_n(self) -> float:
        return self._hook_load_n

    def start_steady(self, top_drive_speed_rad_s: float, hook_load_n: float,
                     perturbation: float = 0.0) -> None:
        """Start exactly on steady drilling at these commands (bit speed times 1 + perturbation);
        a top drive in the loop turns at that speed under the steady torque (torque mode: the
        motor torque command becomes it).

        Raises NoSteadyDrilling, changing nothing, when the weight cannot beat friction, and
        ParameterError when the drive's limits cannot supply the steady torque."""
        rock, layer = self.rock, self.layer
        self._follow_formations(self._start_md_m)      # the start's formation
        try:
            self.steady_state(top_drive_speed_rad_s, hook_load_n)
        except (NoSteadyDrilling, ParameterError):
            self.layer = layer
            self._cut(rock)
            raise
        check_number("top_drive_speed_rad_s", top_drive_speed_rad_s, low_inclusive=True)
        check_number("hook_load_n", hook_load_n, low_inclusive=True)
        self.sim.start_steady(self.w0_of(hook_load_n), self.omega0_of(top_drive_speed_rad_s),
                              perturbation)
        self.command(top_drive_speed_rad_s, hook_load_n)
        self._torque_nm = self.sim.motor_torque_command * self.scales.stiffness_nm_per_rad
        self._forget_samples()

    def start_at_rest(self, gap_m: float = 0.0) -> None:
        """Bit at rest ``gap_m`` above a flat bottom, hanging (hook load = W_s), not rotating."""
        self._follow_formations(self._start_md_m)
        self.sim.start_at_rest(check_number("gap_m", gap_m, low_inclusive=True)
                               / self.scales.length_m)
        self.command(0.0, self.params.submerged_weight_n)
        self._torque_nm = 0.0
        self._forget_samples()

    def steady_state(self, top_drive_speed_rad_s: float, hook_load_n: float) -> SteadyState:
        """The dimensionless steady state at these commands in the rock being cut (the
        formation's; NoSteadyDrilling if none)."""
        return self.sim.steady(self.w0_of(hook_load_n), self.omega0_of(top_drive_speed_rad_s))

    # ---- stepping -----------------------------------------------------------------------
    @property
    def time_s(self) -> float:
        return self.sim.steps * self.dt_s

    def advance_to(self, time_s: float) -> int:
        """Advance to the last step at or before ``time_s``; return the steps taken."""
        if not math.isfinite(time_s):
            raise ParameterError(f"time_s = {time_s!r} is not finite")
        n = math.floor(time_s / self.dt_s + 1e-9) - self.sim.steps
        if n > 0:
            self.sim.advance(n)
        return max(n, 0)

    def advance(self, duration_s: float) -> int:
        return self.advance_to(self.time_s + check_number("duration_s", duration_s,
                                                          low_inclusive=True))

    @property
    def steps(self) -> int:
        """Steps taken since the start (time_s = steps * dt_s)."""
        return self.sim.steps

    def advance_steps(self, n_steps: int) -> None:
        """Advance exactly ``n_steps`` steps (>= 0) with the commands held."""
        if n_steps > 0:
            self.sim.advance(int(n_steps))
            if self._tops:
                self._follow_formations()

    def warm_up(self) -> None:
        """Load the compiled kernel now (a zero-step advance), so the first real step is fast."""
        self.sim.advance(0)

    def reset_metrics_window(self) -> None:
        """Start a new metrics window now (see ``metrics``)."""
        self.sim.reset_window()

    # ---- observation --------------------------------------------------------------------
    def _forget_samples(self) -> None:
        """After a start: no sample interval yet; force sums (SI) carried over a swap."""
        self._pending = (0.0, 0.0, 0)
        self._mean_forces: tuple[float, float] | None = None

    def mean_forces(self) -> tuple[float, float]:
        """(WOB [N], TOB [N m]) averaged over the steps since the previous call, as a sensor
        sampled at these instants reports them: a stick or a landing is an impulse (the rigid
        rock stops the bit within a step), and its mean over the interval does not depend on
        the step. A call with no step since repeats the previous value; the first call after a
        start reads the last step."""
        sum_w, sum_t, n = self.sim.take_force_sums()
        pend_w, pend_t, pend_n = self._pending
        n += pend_n
        if n > 0:
            self._mean_forces = mean_forces(sum_w, sum_t, n, pend_w, pend_t, self._scale_row)
            self._pending = (0.0, 0.0, 0)
        elif self._mean_forces is None:
            x = self.sim.live_state
            self._mean_forces = (float(x[sl.X_W]) * self.scales.force_n,
                                 float(x[sl.X_T]) * self.scales.stiffness_nm_per_rad)
        return self._mean_forces

    def sample(self) -> RigSample:
        """The rig's outputs now, in SI, read straight from the state arrays (the node calls
        this every tick; ``rig_step.sample_into``). WOB and TOB are the means since the
        previous sample (``mean_forces``; the node samples every tick, so the tick mean);
        everything else is the value now."""
        wob_n, tob_nm = self.mean_forces()
        sim = self.sim
        kinematic = sim.drive.mode == "kinematic"
        sample_into(sim.live_state, sim.counts, kinematic, self._speed_rad_s, self._scale_row,
                    self._sample_row)
        (time_s, bit_rad_s, rop_m_s, surface_nm, cut_m, depth_m, hole_m, angle_rad,
         td_angle_rad, td_rad_s, motor_nm, regime) = self._sample_row.tolist()
        regime = int(regime)
        return RigSample(
            time_s=time_s, bit_speed_rad_s=bit_rad_s, rop_m_s=rop_m_s, wob_n=wob_n,
            tob_nm=tob_nm, surface_torque_nm=surface_nm, depth_of_cut_m=cut_m,
            bit_depth_m=depth_m, hole_depth_m=hole_m, bit_angle_rad=angle_rad,
            top_drive_angle_rad=td_angle_rad, top_drive_speed_rad_s=td_rad_s,
            hook_load_n=self._hook_load_n if self.hook_mode == "force"
            else self.measured_hook_load_n,
            stuck=regime == REGIME_STUCK, off_bottom=regime == REGIME_OFF_BOTTOM,
            stick_slip=sim.stick_slip, regime=regime,
            top_drive_speed_setpoint_rad_s=self._speed_rad_s, motor_torque_nm=motor_nm)

    def metrics(self) -> dict[str, float]:
        """Metrics of the current window in SI (see drill_sim.core.metrics)."""
        return self.sim.window_metrics().to_si(self.scales)
