"""The drill string's geometry: sections of tube (pipe, then the BHA), their materials and the
pipe's damping, from which the lumped C, I, M and W_s and the distributed string's wave lines
follow (msg_docs/model.md, "Presets" and "The distributed string")."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields

from .parameters import GRAVITY_M_S2, ParameterError, check_number
from .tube import Tube
from .well import Well, along_hole, normal_force


@dataclass(frozen=True)
class StringSection(Tube):
    """One uniform tube of the string (``Tube``: geometry [m], material [Pa, kg/m^3], None for
    the string's); ``bha``: part of the bottom-hole assembly (rigid in both string models, its
    inertia and mass the BHA's). Its ``keys()`` are a preset's keys of a section."""

    bha: bool = False

    def _check(self) -> None:
        if not isinstance(self.bha, bool):
            raise ParameterError(f"bha = {self.bha!r}: expected true or false")


@dataclass(frozen=True)
class StringGeometry:
    """A drill string, from which the lumped C, I, M and W_s follow: either pipe over collars
    (the two-section keys ``pipe_*``, ``collar_*``) or ``sections``, top first, the BHA's
    (``bha: true``) at the bottom, each with its own material if it says so (else the
    string's: ``shear_modulus_pa``, ``young_modulus_pa``, ``steel_density_kg_m3``).

    Following the model contract (section 8): the pipe is the torsional spring
    (C = 1 / sum(L / (G J)) over the pipe's sections), the BHA is rigid (I = sum rho J L,
    M = sum rho A L over its sections), and the submerged weight is the buoyed weight of the
    whole string. The distributed string (``string_model: distributed``) carries waves along
    the pipe's sections and also takes the pipe's viscous damping per unit length, torsional
    [N m s/rad per m of pipe] and axial [N s/m per m of pipe] (the mud), and its material
    (Kelvin-Voigt) retardation times, torsional and axial [s] (stress G (strain + eta strain
    rate), likewise E): the first damps the low modes, the second the high ones. 0 (the
    defaults here; the shipped presets set them) is a lossless pipe; the lumped model ignores
    them.
    """

    pipe_length_m: float | None = None
    pipe_od_m: float | None = None
    pipe_id_m: float | None = None
    collar_length_m: float | None = None
    collar_od_m: float | None = None
    collar_id_m: float | None = None
    shear_modulus_pa: float = 77e9
    steel_density_kg_m3: float = 8000.0
    mud_density_kg_m3: float = 1200.0
    torsional_damping_nm_s_per_rad_m: float = 0.0
    axial_damping_n_s_per_m2: float = 0.0
    torsional_retardation_time_s: float = 0.0
    axial_retardation_time_s: float = 0.0
    young_modulus_pa: float = 200e9
    sections: tuple[StringSection, ...] = ()
    well: Well | None = None

    def __post_init__(self) -> None:
        shorthand = ("pipe_length_m", "pipe_od_m", "pipe_id_m", "collar_length_m", "collar_od_m",
                     "collar_id_m")
        given = [n for n in shorthand if getattr(self, n) is not None]
        if self.sections and given:
            raise ParameterError(f"{given[0]} with sections: expected either sections or the "
                                 "two-section keys (pipe_*, collar_*), not both")
        if not self.sections and len(given) < len(shorthand):
            missing = [n for n in shorthand if n not in given]
            raise ParameterError(f"{missing[0]} is missing: expected the two-section keys "
                                 f"{', '.join(shorthand)}, or sections")
        for f in fields(self):
            if f.name in ("sections", "well") or (f.name in shorthand and self.sections):
                continue
            object.__setattr__(self, f.name, check_number(
                f.name, getattr(self, f.name),
                low_inclusive=f.name in ("pipe_id_m", "collar_id_m", "mud_density_kg_m3",
                                         "torsional_damping_nm_s_per_rad_m",
                                         "axial_damping_n_s_per_m2",
                                         "torsional_retardation_time_s",
                                         "axial_retardation_time_s")))
        if not self.sections:
            for part in ("pipe", "collar"):
                od, inner = getattr(self, f"{part}_od_m"), getattr(self, f"{part}_id_m")
                if inner >= od:
                    raise ParameterError(f"{part}_id_m = {inner!r} is out of range: expected a "
                                         f"finite number >= 0 and < {part}_od_m = {od!r}")
        else:
            object.__setattr__(self, "sections", tuple(self.sections))
            if not all(isinstance(x, StringSection) for x in self.sections):
                raise ParameterError("sections: expected StringSection entries")
            kinds = [x.bha for x in self.sections]
            if kinds[0] or not kinds[-1] or kinds != sorted(kinds):
                raise ParameterError(
                    "sections: expected the pipe's sections first (at least one) and the BHA's "
                    "(bha: true, at least one) after them, top to bottom; got "
                    + ", ".join("bha" if k else "pipe" for k in kinds))
        if self.well is not None:
            if not isinstance(self.well, Well):
                raise ParameterError("well: expected a Well")
            self.well.check_depth(self.length_m)
        for part in self.parts():
            if self.density(part) <= self.mud_density_kg_m3:
                raise ParameterError(
                    f"mud_density_kg_m3 = {self.mud_density_kg_m3!r} is out of range: expected "
                    f"< the steel's density {self.density(part)!r}")

    def parts(self) -> tuple[StringSection, ...]:
        """The string's sections, top first: ``sections``, or pipe over collars."""
        if self.sections:
            return self.sections
        return (StringSection(self.pipe_length_m, self.pipe_od_m, self.pipe_id_m),
                StringSection(self.collar_length_m, self.collar_od_m, self.collar_id_m, True))

    def pipe(self) -> tuple[StringSection, ...]:
        """The pipe's sections (the elastic string above the BHA), top first."""
        return tuple(x for x in self.parts() if not x.bha)

    def density(self, part: StringSection) -> float:
        return part.steel_density_kg_m3 or self.steel_density_kg_m3

    def shear_modulus(self, part: StringSection) -> float:
        return part.shear_modulus_pa or self.shear_modulus_pa

    def young_modulus(self, part: StringSection) -> float:
        return part.young_modulus_pa or self.young_modulus_pa

    def buoyed_weight_n_m(self, part: StringSection) -> float:
        """A section's buoyed weight per unit length [N/m]."""
        return (self.density(part) - self.mud_density_kg_m3) * GRAVITY_M_S2 * part.area_m2

    @property
    def length_m(self) -> float:
        """The string's length, top to bit [m] (the bit's measured depth)."""
        return float(sum(x.length_m for x in self.parts()))

    def tops_m(self) -> list[float]:
        """Each section's top, measured depth [m]."""
        tops, md = [], 0.0
        for x in self.parts():
            tops.append(md)
            md += x.length_m
        return tops

    def hanging_tension_n(self, md_m: float) -> float:
        """The effective tension [N] at measured depth ``md_m`` of the string hanging off bottom:
        the buoyed weight of what hangs below, along the hole's axis."""
        well = self.well or Well()
        tops, below = self.tops_m(), []
        for top, x in zip(tops, self.parts(), strict=True):
            start, end = max(top, md_m), top + x.length_m
            if end > start:
                below.append((start, end - start, self.buoyed_weight_n_m(x)))
        if not below:
            return 0.0
        starts, lengths, weights = zip(*below, strict=True)
        return float(sum(along_hole(well, list(starts), list(lengths), list(weights))))

    def wall_forces_n_m(self, part_index: int, fractions: Sequence[float]) -> list[float]:
        """The soft string's wall force per unit length [N/m] at ``fractions`` of section
        ``part_index``'s length (hanging off bottom; none in a vertical hole or without a
        survey)."""
        well = self.well
        x = self.parts()[part_index]
        if well is None or not well.survey:
            return [0.0] * len(fractions)
        top = self.tops_m()[part_index]
        out = []
        for f in fractions:
            md = top + f * x.length_m
            out.append(normal_force(well, md, self.hanging_tension_n(md),
                                    self.buoyed_weight_n_m(x)))
        return out

    @property
    def pipe_length_total_m(self) -> float:
        """Length of the pipe above the BHA [m]."""
        return float(sum(x.length_m for x in self.pipe()))

    @property
    def torsional_impedance_nm_s_rad(self) -> float:
        """The top pipe section's torsional impedance Z = J sqrt(G rho) [N m s/rad] (model
        contract, section 9): the torque per unit speed a torsional wave carries along it,
        what the top drive sees."""
        top = self.parts()[0]
        return top.polar_moment_m4 * math.sqrt(self.shear_modulus(top) * self.density(top))

    def lumped(self) -> dict[str, float]:
        """C [N m/rad], I [kg m^2], M [kg] and W_s [N] of this string (one pipe section: C =
        G J / L as written, one steel: W_s = (rho - rho_mud) g V, to the last bit)."""
        pipe = self.pipe()
        if len(pipe) == 1:
            c = self.shear_modulus(pipe[0]) * pipe[0].polar_moment_m4 / pipe[0].length_m
        else:
            c = 1.0 / sum(x.length_m / (self.shear_modulus(x) * x.polar_moment_m4) for x in pipe)
        bha = [x for x in self.parts() if x.bha]
        volumes: dict[float, float] = {}                 # steel volume by density
        for x in self.parts():
            volumes[self.density(x)] = volumes.get(self.density(x), 0.0) + x.area_m2 * x.length_m
        return {
            "torsional_stiffness_nm_per_rad": c,
            "bha_inertia_kg_m2": sum(self.density(x) * x.polar_moment_m4 * x.length_m
                                     for x in bha),
            "bha_mass_kg": sum(self.density(x) * x.area_m2 * x.length_m for x in bha),
            "submerged_weight_n": self._submerged_weight_n(volumes),
        }

    def _submerged_weight_n(self, volumes: dict[float, float]) -> float:
        """W_s: the buoyed weight along the hole's axis at the bit (a vertical hole: the whole
        buoyed weight, (rho - rho_mud) g V to the last bit; a survey: sum w_i int cos(incl))."""
        if self.well is None or not self.well.survey:
            return sum((rho - self.mud_density_kg_m3) * GRAVITY_M_S2 * volume
                       for rho, volume in volumes.items())
        parts = self.parts()
        return float(sum(along_hole(self.well, self.tops_m(), [x.length_m for x in parts],
                                    [self.buoyed_weight_n_m(x) for x in parts])))
