"""Model parameters in SI and as the dimensionless groups of the RGD scaling.

The core integrates the dimensionless equations (model contract, section 3); users give either
SI parameters (lumped, or from the string geometry) or the groups (n, psi, lambda, beta)
directly. Every constructor validates its inputs so that a bad value is refused with a
message naming the parameter, its value and the allowed range, before anything runs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

import numpy as np

GRAVITY_M_S2 = 9.80665


class ParameterError(ValueError):
    """A parameter or command is missing, non-finite or out of its allowed range."""


def check_number(name: str, value: object, *, low: float | None = 0.0,
                 low_inclusive: bool = False, high: float | None = None) -> float:
    """Return ``value`` as a float, or raise ParameterError naming it and the allowed range
    (true and false are not numbers, though Python counts them as 1 and 0)."""
    if isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name} = {value!r} is not a number: expected "
                             f"{_range_text(low, low_inclusive, high)}")
    if not isinstance(value, (int, float)):
        try:
            value = float(value)  # numpy scalars, numeric strings from YAML
        except (TypeError, ValueError):
            raise ParameterError(f"{name} = {value!r} is not a number: expected "
                                 f"{_range_text(low, low_inclusive, high)}") from None
    value = float(value)
    bad = not math.isfinite(value)
    if not bad and low is not None:
        bad = value < low if low_inclusive else value <= low
    if not bad and high is not None:
        bad = value > high
    if bad:
        raise ParameterError(f"{name} = {value!r} is out of range: expected "
                             f"{_range_text(low, low_inclusive, high)}")
    return value


def check_blade_count(value: object) -> int:
    """The blade count must be a whole number from 1 to 64."""
    if isinstance(value, bool):
        raise ParameterError(f"n (blade count) = {value!r} is not a whole number: "
                             "expected an integer 1..64")
    try:
        as_float = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"n (blade count) = {value!r} is not a whole number: "
                             "expected an integer 1..64") from None
    if not math.isfinite(as_float) or as_float != int(as_float) or not 1 <= as_float <= 64:
        raise ParameterError(f"n (blade count) = {value!r} is out of range: "
                             "expected an integer 1..64")
    return int(as_float)


def _range_text(low: float | None, low_inclusive: bool, high: float | None) -> str:
    parts = []
    if low is not None:
        parts.append(f"{'>=' if low_inclusive else '>'} {low:g}")
    if high is not None:
        parts.append(f"<= {high:g}")
    return "a finite number " + " and ".join(parts) if parts else "a finite number"


@dataclass(frozen=True)
class Groups:
    """The dimensionless groups of the model contract (section 3).

    n: blade count; psi: axial-to-torsional inertia ratio; lam (lambda): wear-flat friction
    weight over F*; beta = mu * gamma * zeta: friction-to-cutting torque ratio.
    Stick-slip appears only for beta < 1.
    """

    n: int
    psi: float
    lam: float
    beta: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "n", check_blade_count(self.n))
        object.__setattr__(self, "psi", check_number("psi", self.psi))
        object.__setattr__(self, "lam", check_number("lambda", self.lam, low_inclusive=True))
        object.__setattr__(self, "beta", check_number("beta", self.beta, low_inclusive=True))


@dataclass(frozen=True)
class Scales:
    """Reference scales that turn dimensionless quantities into SI (model contract, section 3)."""

    time_s: float             # t* = sqrt(I/C)
    length_m: float           # L* = 2C/(eps a^2)
    force_n: float            # F* = a zeta eps L*
    stiffness_nm_per_rad: float  # C: torque scale [N m]

    @property
    def velocity_m_s(self) -> float:
        return self.length_m / self.time_s

    @property
    def angular_velocity_rad_s(self) -> float:
        return 1.0 / self.time_s


def friction_torque_ratio(mu: float, gamma: float, zeta: float) -> float:
    """beta = mu gamma zeta: the wear flats' friction torque over the cutting torque at the same
    weight (model contract, section 3), of the friction coefficient mu, the wear flats'
    orientation gamma and the cutting face's inclination zeta (all [-])."""
    return mu * gamma * zeta


@dataclass(frozen=True)
class RigParameters:
    """Lumped SI parameters of bit, rock and drill string (model contract, sections 1-2)."""

    bit_radius_m: float                  # a
    blade_count: int                     # n
    intrinsic_specific_energy_pa: float  # epsilon
    cutting_inclination: float           # zeta [-]
    contact_stress_pa: float             # sigma
    wear_flat_length_m: float            # l, total over all blades
    friction_coefficient: float          # mu [-]
    wear_flat_orientation: float         # gamma [-]
    bha_mass_kg: float                   # M
    bha_inertia_kg_m2: float             # I
    torsional_stiffness_nm_per_rad: float  # C
    submerged_weight_n: float            # W_s

    def __post_init__(self) -> None:
        object.__setattr__(self, "blade_count", check_blade_count(self.blade_count))
        for f in fields(self):
            if f.name == "blade_count":
                continue
            low_inclusive = f.name in ("wear_flat_length_m", "friction_coefficient",
                                       "wear_flat_orientation", "contact_stress_pa")
            object.__setattr__(self, f.name, check_number(f.name, getattr(self, f.name),
                                                          low_inclusive=low_inclusive))

    @property
    def scales(self) -> Scales:
        a, eps, zeta, c = (self.bit_radius_m, self.intrinsic_specific_energy_pa,
                           self.cutting_inclination, self.torsional_stiffness_nm_per_rad)
        length = 2.0 * c / (eps * a * a)
        return Scales(time_s=math.sqrt(self.bha_inertia_kg_m2 / c), length_m=length,
                      force_n=a * zeta * eps * length, stiffness_nm_per_rad=c)

    @property
    def groups(self) -> Groups:
        a, eps, zeta, c = (self.bit_radius_m, self.intrinsic_specific_energy_pa,
                           self.cutting_inclination, self.torsional_stiffness_nm_per_rad)
        length = self.scales.length_m
        return Groups(
            n=self.blade_count,
            psi=a * zeta * eps * self.bha_inertia_kg_m2 / (self.bha_mass_kg * c),
            lam=self.wear_flat_length_m * self.contact_stress_pa / (zeta * eps * length),
            beta=friction_torque_ratio(self.friction_coefficient, self.wear_flat_orientation,
                                       zeta),
        )

    @property
    def friction_weight_n(self) -> float:
        """Fully mobilised wear-flat weight a*l*sigma [N]: below it there is no drilling."""
        return self.bit_radius_m * self.wear_flat_length_m * self.contact_stress_pa

    def with_groups(self, groups: Groups) -> RigParameters:
        """The same bit, rock and string stiffness, with M, l and mu changed to match ``groups``.

        This is the SI direction of the conversion: the groups fix three ratios, so three
        SI parameters (BHA mass, wear-flat length, friction coefficient) are solved for.
        """
        if groups.n != self.blade_count:
            return replace(self, blade_count=groups.n).with_groups(groups)
        a, eps, zeta, c = (self.bit_radius_m, self.intrinsic_specific_energy_pa,
                           self.cutting_inclination, self.torsional_stiffness_nm_per_rad)
        length = self.scales.length_m
        return replace(
            self,
            bha_mass_kg=a * zeta * eps * self.bha_inertia_kg_m2 / (groups.psi * c),
            wear_flat_length_m=groups.lam * zeta * eps * length / self.contact_stress_pa,
            friction_coefficient=groups.beta / (self.wear_flat_orientation * zeta),
        )

    def as_dict(self) -> dict[str, float]:
        return {f.name: getattr(self, f.name) for f in fields(self)}
