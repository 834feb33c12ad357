"""A uniform tube of the drill string, SI: length, outer and inner diameter [m] and material
(shear and Young's moduli [Pa], density [kg/m^3]), checked here once, with its polar moment of
area [m^4] and cross-section [m^2]. The string's sections (``string_geometry.StringSection``)
and the distributed string's (``distributed.Section``) are tubes."""

from __future__ import annotations

import math
from dataclasses import KW_ONLY, dataclass, fields

from .parameters import ParameterError, check_number

MATERIAL = ("shear_modulus_pa", "young_modulus_pa", "steel_density_kg_m3")


@dataclass(frozen=True)
class Tube:
    """A uniform tube, SI: length, outer and inner diameter [m] (0 <= id < od); its material,
    keyword-only, None for the string's: shear and Young's moduli [Pa] and density [kg/m^3]
    (``steel_density_kg_m3``, the presets' key, whatever the metal). A subclass's own fields
    come after the geometry in its constructor (the material stays last) and are checked in
    ``_check``, between the geometry's checks and the material's."""

    length_m: float
    od_m: float
    id_m: float
    _: KW_ONLY
    shear_modulus_pa: float | None = None
    young_modulus_pa: float | None = None
    steel_density_kg_m3: float | None = None

    def __post_init__(self) -> None:
        for name in ("length_m", "od_m", "id_m"):
            object.__setattr__(self, name, check_number(name, getattr(self, name),
                                                        low_inclusive=name == "id_m"))
        if self.id_m >= self.od_m:
            raise ParameterError(f"id_m = {self.id_m!r} is out of range: expected a finite "
                                 f"number >= 0 and < od_m = {self.od_m!r}")
        self._check()
        for name in MATERIAL:
            if getattr(self, name) is not None:
                object.__setattr__(self, name, check_number(name, getattr(self, name)))

    def _check(self) -> None:
        """A subclass's own fields (the tube has none)."""

    @classmethod
    def keys(cls) -> tuple[str, ...]:
        """The field names in the constructor's order: the geometry, a subclass's own fields,
        the material."""
        return tuple(f.name for f in sorted(fields(cls), key=lambda f: f.kw_only))

    def given(self) -> dict[str, object]:
        """The fields given (not None), in ``keys()`` order, for records."""
        return {k: getattr(self, k) for k in self.keys() if getattr(self, k) is not None}

    @property
    def polar_moment_m4(self) -> float:
        """The polar moment of area [m^4]."""
        return math.pi / 32.0 * (self.od_m**4 - self.id_m**4)

    @property
    def area_m2(self) -> float:
        """The cross-section [m^2]."""
        return math.pi / 4.0 * (self.od_m**2 - self.id_m**2)
