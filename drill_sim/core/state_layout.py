"""One declaration of the rig's state: every slot of the kernels' flat arrays.

The kernels keep their state, parameters, commands, window integrals and output rows in six
flat arrays (``x``, ``k``, ``p``, ``c``, ``a``, ``o``). Each array is a ``Block`` of ``Slot``s:
a slot's key (the kernels' constant is the block's prefix and the key: ``X_TAU``), its name
(the model contract's, as ``StateView`` and ``Trajectory`` spell it), its dimensionless unit
(a ``Dimension``: how it scales to SI and how it is carried to other scales) and the string
model that adds it. The lumped string's slots come first; the distributed string appends its
own, so a lumped index means the same in both.

The integer constants (``X_TAU``, ``NX``, ``NXD`` ...) are made here from the tables at import,
so numba still sees constants. Adding a slot is one line in its block and its use in the
kernels that step it (a lumped slot is the distributed string's too: the same bit, BHA and
drive, stepped by ``kernel`` and by ``distributed_kernel``): the state view,
``Simulator.save_state``/``load_state``, the conversions between scales
(``Rig.replace_parameters``) and the vector environment's stacking read the tables. A slot
that is bookkeeping, not physical state, is declared ``view=False``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .parameters import Scales

LUMPED, DISTRIBUTED = "lumped", "distributed"
STRING_MODELS = (LUMPED, DISTRIBUTED)


@dataclass(frozen=True)
class Dimension:
    """A dimensionless unit: its symbol, its SI unit and its SI scale t*^a L*^b C^c F*^d (the
    scale's exponents of time, length, torque and force)."""

    symbol: str
    si_unit: str
    time: int = 0
    length: int = 0
    torque: int = 0
    force: int = 0

    def si_factor(self, scales: Scales) -> float:
        """SI per dimensionless unit at ``scales``."""
        return (scales.time_s ** self.time * scales.length_m ** self.length
                * scales.stiffness_nm_per_rad ** self.torque * scales.force_n ** self.force)

    def rescale(self, value: float, old: Scales, new: Scales) -> float:
        """``value`` at the ``old`` scales as a value at the ``new`` ones (the same SI
        quantity). Written per unit as the conversions were first written, so a run carried
        to new parameters is the same to the bit."""
        if self is TIME:
            return value * old.time_s / new.time_s
        if self is RATE:
            return value * new.time_s / old.time_s
        if self is LENGTH:
            return value * (old.length_m / new.length_m)
        if self is VELOCITY:
            return value * old.velocity_m_s / new.velocity_m_s
        if self is FORCE:
            return value * old.force_n / new.force_n
        if self is TORQUE:
            return value * (old.stiffness_nm_per_rad / new.stiffness_nm_per_rad)
        if self is PURE:
            return value
        return value * (self.si_factor(old) / self.si_factor(new))


PURE = Dimension("-", "-")                           # counts, flags, angles [rad], ratios
TIME = Dimension("t*", "s", time=1)
RATE = Dimension("1/t*", "rad/s", time=-1)          # angular speeds
ANGULAR_ACCELERATION = Dimension("1/t*^2", "rad/s^2", time=-2)
LENGTH = Dimension("L*", "m", length=1)
VELOCITY = Dimension("L*/t*", "m/s", length=1, time=-1)
ACCELERATION = Dimension("L*/t*^2", "m/s^2", length=1, time=-2)
TORQUE = Dimension("C", "N m", torque=1)            # torques (C times 1 rad)
FORCE = Dimension("F*", "N", force=1)
TORQUE_RATE = Dimension("C/t*", "N m/s", torque=1, time=-1)
TORQUE_TIME = Dimension("C t*", "N m s", torque=1, time=1)    # gains, torque impulses
ENERGY_AXIAL = Dimension("F* L*", "J", force=1, length=1)
IMPULSE = Dimension("F* t*", "N s", force=1, time=1)
INERTIA = Dimension("I", "kg m^2")                   # the BHA's inertia I (C t*^2)


@dataclass(frozen=True)
class Slot:
    """One entry of a flat array: ``key`` (the constant's suffix), ``name`` (the model
    contract's), its unit, the string model that adds it and what it holds."""

    key: str
    name: str
    unit: Dimension
    doc: str
    model: str = LUMPED
    view: bool = True        # part of the physical state (``StateView``), not bookkeeping


class Block:
    """One flat array of the kernels: its constants' ``prefix`` (``X``), its dtype and its
    slots, the lumped string's first."""

    def __init__(self, prefix: str, dtype: type, slots: tuple[Slot, ...]) -> None:
        models = [STRING_MODELS.index(s.model) for s in slots]
        if models != sorted(models):
            raise ValueError(f"block {prefix}: a distributed slot before a lumped one")
        keys = [s.key for s in slots]
        if len(set(keys)) != len(keys):
            raise ValueError(f"block {prefix}: a key declared twice")
        self.prefix, self.dtype, self.slots = prefix, dtype, slots
        self._index = {s.key: i for i, s in enumerate(slots)}
        self._names = {s.name: i for i, s in enumerate(slots)}

    def size(self, model: str = LUMPED) -> int:
        """The array's length for ``model`` (a model holds its own slots and those before)."""
        level = STRING_MODELS.index(model)
        return sum(1 for s in self.slots if STRING_MODELS.index(s.model) <= level)

    def of(self, model: str) -> tuple[Slot, ...]:
        """The slots ``model`` holds, in order."""
        return self.slots[:self.size(model)]

    def index(self, name: str) -> int:
        """The index of the slot named ``name`` (the contract's name)."""
        return self._names[name]

    def empty(self, model: str = LUMPED) -> np.ndarray:
        """A zeroed array for ``model``."""
        return np.zeros(self.size(model), dtype=self.dtype)

    def constants(self) -> dict[str, int]:
        """``PREFIX_KEY`` -> index for every slot; ``NPREFIX`` the lumped size, ``NPREFIXD``
        the distributed one."""
        out = {f"{self.prefix}_{s.key}": i for i, s in enumerate(self.slots)}
        out[f"N{self.prefix}"] = self.size(LUMPED)
        out[f"N{self.prefix}D"] = self.size(DISTRIBUTED)
        return out


def _lumped(*rows: tuple) -> tuple[Slot, ...]:
    return tuple(Slot(*row) for row in rows)


def _distributed(*rows: tuple) -> tuple[Slot, ...]:
    return tuple(Slot(*row, model=DISTRIBUTED) for row in rows)


# float state x
STATE = Block("X", np.float64, _lumped(
    ("TAU", "tau", TIME, "time"),
    ("U", "u", LENGTH, "bit's axial position, positive downhole"),
    ("V", "v", VELOCITY, "bit's axial velocity"),
    ("PHI", "phi", PURE, "bit's angle [rad]"),
    ("OMEGA", "omega", RATE, "bit's angular speed"),
    ("PHI_TD", "phi_td", PURE, "top drive's angle [rad]"),
    ("S_BEHIND", "surface_behind", LENGTH,
     "rock surface at the last node the blades passed, from before this pass"),
    ("SINCE_STICK", "since_stick", TIME, "time since the bit was last stuck"),
    ("W", "w", FORCE, "weight on bit during the last step"),
    ("T", "t", TORQUE, "torque on bit during the last step"),
    ("TS", "ts", TORQUE, "string (surface) torque at the end of the last step"),
    ("DELTA", "delta_n", LENGTH, "depth of cut per blade during the last step"),
    ("G", "g", PURE, "wear-flat contact factor during the last step"),
    ("HOLE", "hole_bottom", LENGTH, "deepest point of the rock surface, max of S"),
    ("SUM_W", "sum_w", FORCE, "sum of w over the steps since the last sample (an output row or "
     "a read of the sums); the window's A_W excludes it", LUMPED, False),
    ("SUM_T", "sum_t", TORQUE, "sum of t likewise", LUMPED, False),
    ("OMEGA_TD", "omega_td", RATE, "top drive's speed (kinematic mode: omega0)"),
    ("DRIVE_I", "drive_integral", TORQUE, "the speed PI's integral term"),
    ("TM", "motor_torque", TORQUE, "motor torque at the end of the last step, after limits "
     "and lag"),
    ("TREF", "drive_reference", TORQUE, "the drive's reference after rate limit and "
     "saturation (the lag's input)"),
) + _distributed(
    ("T_BOTTOM", "bottom_torque", TORQUE, "the pipe's torque on the BHA over the last step"),
    ("F_BOTTOM", "bottom_force", FORCE, "the pipe's force on the BHA over the last step"),
    ("V_TOP", "top_velocity", VELOCITY, "the string's top axial speed"),
    ("F_TOP", "top_force", FORCE, "the force the string's top takes from the hook"),
    ("DOM", "bha_angular_acceleration", ANGULAR_ACCELERATION,
     "the BHA's angular acceleration over the last step"),
    ("DV", "bha_acceleration", ACCELERATION, "the BHA's axial acceleration over the last step"),
    ("A_PREV", "arriving_torque", TORQUE, "the torsional invariant that arrived at the BHA "
     "last step"),
    ("BHA_WALL_T", "bha_wall_torque", TORQUE, "the wall's torque on the BHA"),
    ("BHA_WALL_F", "bha_wall_force", FORCE, "the wall's axial force on the BHA"),
))

# integer state k
COUNTS = Block("K", np.int64, _lumped(
    ("LAST", "last_node", PURE, "absolute index of the last surface node the blades passed"),
    ("REGIME", "regime", PURE, "REGIME_* of the last step"),
    ("STEPS", "steps", PURE, "steps taken since the start"),
    ("SAMPLED", "sampled", PURE, "K_STEPS at the last sample (X_SUM_* cover the steps since)"),
    ("REFUSED", "refused", PURE, "1 if the last call stopped before a step turning the bit "
     "over a sector"),
))

# parameters p (the top drive's: top_drive.DriveGroups; LAG_END, LAG_MEAN its lag's weights
# over a whole step)
PARAMETERS = Block("P", np.float64, _lumped(
    ("N", "n", PURE, "blade count times the rock's cutting factor"),
    ("PSI", "psi", PURE, "psi"),
    ("LAM", "lam", PURE, "lambda"),
    ("BETA", "beta", PURE, "beta = mu gamma zeta"),
    ("H", "h", TIME, "the step"),
    ("DTHETA", "dtheta", PURE, "the rock surface's node spacing [rad]"),
    ("INV_DTHETA", "inv_dtheta", PURE, "1/dtheta [1/rad]"),
    ("MODE", "mode", PURE, "the top drive's MODE_*"),
    ("J", "j", INERTIA, "the top drive's inertia"),
    ("T_MAX", "t_max", TORQUE, "the motor's upper torque limit"),
    ("T_MIN", "t_min", TORQUE, "the motor's lower torque limit"),
    ("RATE", "rate", TORQUE_RATE, "the motor torque's rate limit"),
    ("LAG", "lag", TIME, "the motor torque's lag"),
    ("KP", "kp", TORQUE_TIME, "the speed PI's proportional gain"),
    ("KI", "ki", TORQUE, "the speed PI's integral gain"),
    ("LAG_END", "lag_end", PURE, "the lag's weight of the step's end"),
    ("LAG_MEAN", "lag_mean", PURE, "the lag's weight of the step's mean"),
))

# commands c (zero-order hold between calls); OMEGA0 is the drive's set-point in speed mode
COMMANDS = Block("C", np.float64, _lumped(
    ("W0", "w0", FORCE, "available weight on bit"),
    ("OMEGA0", "omega0", RATE, "top-drive speed command"),
    ("V_MIN", "v_min", VELOCITY, "lowest axial velocity (the hoisting-speed limit)"),
    ("T_CMD", "motor_torque_command", TORQUE, "motor torque command, torque mode"),
) + _distributed(
    ("HOOK_POSITION", "hook_position", PURE, "the hook's mode: 0 force (the hook holds w0), 1 "
     "position (the block moves at C_V_BLOCK)"),
    ("V_BLOCK", "block_speed", VELOCITY, "the block's speed, positive down"),
    ("TOP_ABSORB", "top_absorb", PURE, "1: the top reflects nothing (kinematic mode only)"),
    ("TOP_LEVEL", "top_level", TORQUE, "the torsional invariant the absorbing top sends down"),
    ("TOP_T_MIN", "top_t_min", TORQUE, "the absorbing top's lower torque limit"),
    ("TOP_T_MAX", "top_t_max", TORQUE, "the absorbing top's upper torque limit"),
))

# window integrals a (A_W, A_T up to the last sample: add h X_SUM_W, h X_SUM_T for the window's)
WINDOW = Block("A", np.float64, _lumped(
    ("TIME", "time", TIME, "the window's length"),
    ("OMEGA", "omega", PURE, "integral of the bit's speed [rad]"),
    ("OMEGA_MIN", "omega_min", RATE, "the bit's lowest speed"),
    ("OMEGA_MAX", "omega_max", RATE, "the bit's highest speed"),
    ("W", "w", IMPULSE, "integral of the weight on bit"),
    ("T", "t", TORQUE_TIME, "integral of the torque on bit"),
    ("TS", "ts", TORQUE_TIME, "integral of the surface torque"),
    ("V", "v", LENGTH, "integral of the axial velocity"),
    ("STICK_TIME", "stick_time", TIME, "time stuck"),
    ("BOUNCE_TIME", "bounce_time", TIME, "time off bottom"),
    ("WORK_TOP_DRIVE", "work_top_drive", TORQUE, "work of the string's top torque"),
    ("WORK_WEIGHT", "work_weight", ENERGY_AXIAL, "work of the available weight"),
    ("WORK_HOIST", "work_hoist", ENERGY_AXIAL, "work of the hoist's force"),
    ("DISSIPATED_ROT", "dissipated_rotation", TORQUE, "energy the bit dissipated turning"),
    ("DISSIPATED_AX", "dissipated_axial", ENERGY_AXIAL, "energy the bit dissipated axially"),
    ("W0", "w0", IMPULSE, "integral of the available weight"),
    ("OMEGA0", "omega0", PURE, "integral of the speed command [rad]"),
    ("OMEGA_TD", "omega_td", PURE, "integral of the top drive's speed [rad]"),
    ("TM", "motor_torque", TORQUE_TIME, "integral of the motor torque"),
    ("WORK_MOTOR", "work_motor", TORQUE, "work of the motor"),
) + _distributed(
    ("DAMPED_ROT", "damped_rotation", TORQUE, "energy the pipe's damping dissipated turning"),
    ("DAMPED_AX", "damped_axial", ENERGY_AXIAL, "energy the pipe's damping dissipated axially"),
    ("LOSS_ROT", "loss_rotation", TORQUE, "energy the transport's weighting dissipated, "
     "torsional"),
    ("LOSS_AX", "loss_axial", ENERGY_AXIAL, "likewise axial"),
    ("WALL_ROT", "wall_rotation", TORQUE, "energy the wall's friction dissipated, torsional"),
    ("WALL_AX", "wall_axial", ENERGY_AXIAL, "likewise axial"),
))

# output rows o (W, T: means over the steps since the previous sample or row)
OUTPUTS = Block("O", np.float64, _lumped(
    ("TAU", "tau", TIME, "time"),
    ("U", "u", LENGTH, "bit's axial position"),
    ("V", "v", VELOCITY, "bit's axial velocity"),
    ("PHI", "phi", PURE, "bit's angle [rad]"),
    ("OMEGA", "omega", RATE, "bit's angular speed"),
    ("PHI_TD", "phi_td", PURE, "top drive's angle [rad]"),
    ("W", "w", FORCE, "weight on bit, mean over the row's interval"),
    ("T", "t", TORQUE, "torque on bit, mean over the row's interval"),
    ("TS", "ts", TORQUE, "surface torque"),
    ("DELTA", "delta_n", LENGTH, "depth of cut per blade"),
    ("REGIME", "regime", PURE, "REGIME_* of the last step"),
    ("W0", "w0", FORCE, "available weight"),
    ("OMEGA0", "omega0", RATE, "speed command"),
    ("G", "g", PURE, "wear-flat contact factor"),
    ("OMEGA_TD", "omega_td", RATE, "top drive's speed (kinematic mode: omega0)"),
    ("TM", "motor_torque", TORQUE, "motor torque (kinematic mode: the string torque, which "
     "imposes omega0)"),
) + _distributed(
    ("T_BOTTOM", "bottom_torque", TORQUE, "the pipe's torque on the BHA"),
    ("F_BOTTOM", "bottom_force", FORCE, "the pipe's force on the BHA"),
    ("V_TOP", "top_velocity", VELOCITY, "the string's top axial speed"),
    ("F_TOP", "top_force", FORCE, "the force at the string's top"),
))

BLOCKS = (STATE, COUNTS, PARAMETERS, COMMANDS, WINDOW, OUTPUTS)

for _block in BLOCKS:        # X_TAU, NX, NXD, ...: constants, as numba compiles them
    globals().update(_block.constants())
del _block
