"""Named parameter sets shipped with the package, and the same format read from any YAML file.

A preset file has a ``bit`` section (bit and rock, SI), either a ``string`` section (pipe and
collar geometry, or a list of ``sections``, from which C, I, M and W_s are computed) or a
``lumped`` section (those four directly), optional default ``commands``
(``top_drive_speed_rpm``, ``weight_on_bit_kn``) and an optional ``top_drive`` section
(``TopDriveParameters``' fields; the drive's proportional gain defaults to 50 Z, Z the top
pipe section's torsional impedance, when the string's geometry is given).
An optional ``string_model: lumped | distributed`` (default lumped) picks the string's model;
``distributed`` needs the ``string`` geometry. An optional ``commissioning`` section holds
Z-Torque's gains as set on this string for a drive's signals, over the reference rule's
(``control.reference``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path

from .distributed import check_string_model
from .parameters import ParameterError, RigParameters, check_number
from .resources import read_yaml, shipped_names
from .string_geometry import StringGeometry, StringSection
from .top_drive import KP_PER_IMPEDANCE, TopDriveParameters
from .well import Well

_BIT_KEYS = ("bit_radius_m", "blade_count", "intrinsic_specific_energy_pa", "cutting_inclination",
             "contact_stress_pa", "wear_flat_length_m", "friction_coefficient",
             "wear_flat_orientation")
_LUMPED_KEYS = ("bha_mass_kg", "bha_inertia_kg_m2", "torsional_stiffness_nm_per_rad",
                "submerged_weight_n")


@dataclass(frozen=True)
class Preset:
    """A named rig: its SI parameters and the surface commands it is usually run at."""

    name: str
    description: str
    rig: RigParameters
    string: StringGeometry | None
    top_drive_speed_rpm: float
    weight_on_bit_kn: float
    top_drive: TopDriveParameters = field(default_factory=TopDriveParameters)
    string_model: str = "lumped"      # "lumped" or "distributed" (needs ``string``)
    # gains set on this string for a drive's signals, by law (z_torque: control.reference):
    # ((law, ((gain, value), ...)), ...), a tuple so that a preset stays hashable
    commissioning: tuple[tuple[str, tuple[tuple[str, float], ...]], ...] = ()

    def commissioned(self, law: str) -> dict[str, float]:
        """The gains the ``commissioning`` section sets for ``law`` (empty: none)."""
        return dict(dict(self.commissioning).get(law, ()))

    @property
    def top_drive_speed_rad_s(self) -> float:
        return self.top_drive_speed_rpm * 2.0 * math.pi / 60.0

    @property
    def hook_load_n(self) -> float:
        """Hook load H0 [N] that leaves the default weight on bit: H0 = W_s - WOB."""
        return self.rig.submerged_weight_n - 1e3 * self.weight_on_bit_kn


def preset_names() -> list[str]:
    """Names of the presets shipped with the package."""
    return shipped_names("presets")


def load_preset(name_or_path: str | Path) -> Preset:
    """Load a shipped preset by name (``base``, ``shallow``, ``deep``) or any preset YAML file."""
    return preset_from_dict(*read_yaml("preset", "presets", name_or_path))


def preset_from_dict(name: str, data: object) -> Preset:
    """Build a preset from the parsed YAML mapping, refusing missing or unknown keys."""
    if not isinstance(data, dict):
        raise ParameterError(f"preset {name!r}: expected a mapping with 'bit' and 'string' or "
                             f"'lumped' sections, got {type(data).__name__}")
    bit = _section(name, data, "bit", _BIT_KEYS, required=True)
    string = None
    if "string" in data:
        string = string_from_dict(name, data["string"], data.get("well"))
        lumped = string.lumped()
    elif "well" in data:
        raise ParameterError(f"preset {name!r}: a 'well' section needs a 'string' section (the "
                             "string's geometry); a 'lumped' section has none")
    else:
        lumped = _section(name, data, "lumped", _LUMPED_KEYS, required=True)
    commands = _section(name, data, "commands", ("top_drive_speed_rpm", "weight_on_bit_kn"),
                        required=False, need=())
    drive = _section(name, data, "top_drive", tuple(f.name for f in fields(TopDriveParameters)),
                     required=False, need=())
    if string is not None and drive.get("drive_kp_nm_s_rad") is None:
        drive["drive_kp_nm_s_rad"] = KP_PER_IMPEDANCE * string.torsional_impedance_nm_s_rad
    unknown = set(data) - {"description", "bit", "string", "lumped", "well", "commands",
                           "top_drive", "string_model", "commissioning"}
    if unknown:
        raise ParameterError(f"preset {name!r}: unknown section(s) {sorted(unknown)}; expected "
                             "description, bit, string or lumped, well, commands, top_drive, "
                             "string_model, commissioning")
    string_model = _string_model(name, data.get("string_model", "lumped"), string)
    return Preset(
        name=name,
        description=str(data.get("description", "")),
        rig=RigParameters(**bit, **lumped),
        string=string,
        top_drive_speed_rpm=check_number("top_drive_speed_rpm",
                                         commands.get("top_drive_speed_rpm", 60.0)),
        weight_on_bit_kn=check_number("weight_on_bit_kn", commands.get("weight_on_bit_kn", 100.0),
                                      low_inclusive=True),
        top_drive=TopDriveParameters(**drive),
        string_model=string_model,
        commissioning=_commissioning(name, data.get("commissioning")),
    )


_SECTION_KEYS = StringSection.keys()


_WELL_KEYS = ("survey", "friction_static", "friction_dynamic", "formations")


def well_from_dict(name: str, well: object) -> Well:
    """A preset's ``well`` section: ``survey`` (rows [measured depth m, inclination deg,
    azimuth deg], the first at 0 m, down to the bit), ``friction_static`` and
    ``friction_dynamic`` (the string against the wall; the rule between them is Coulomb's,
    exact: a part of the string at rest stays there while the wall can hold it),
    ``formations`` (layers by increasing ``top_m``, each with the rock values that change
    there: ``Formation``)."""
    given = _section(name, {"well": well}, "well", _WELL_KEYS, required=True, need=())
    survey = given.get("survey", [])
    if not isinstance(survey, list):
        raise ParameterError(f"preset {name!r}: well.survey is {type(survey).__name__}: "
                             "expected a list of rows [measured depth m, inclination deg, "
                             "azimuth deg]")
    formations = given.get("formations", [])
    if not isinstance(formations, list):
        raise ParameterError(f"preset {name!r}: well.formations is "
                             f"{type(formations).__name__}: expected a list of layers "
                             "({top_m: m, and any of intrinsic_specific_energy_pa, "
                             "contact_stress_pa, friction_coefficient}), by increasing top")
    try:
        return Well(survey=tuple(tuple(r) if isinstance(r, list) else r for r in survey),
                    friction_static=given.get("friction_static", 0.0),
                    friction_dynamic=given.get("friction_dynamic",
                                               given.get("friction_static", 0.0)),
                    formations=tuple(formations))
    except ParameterError as exc:
        raise ParameterError(f"preset {name!r}: well: {exc}") from None


def string_from_dict(name: str, string: object, well: object = None) -> StringGeometry:
    """A preset's ``string`` section: the two-section keys (``pipe_*``, ``collar_*``) or
    ``sections``, a list of ``{length_m, od_m, id_m, bha, shear_modulus_pa, young_modulus_pa,
    steel_density_kg_m3}`` (the last four optional), top first; in the hole ``well``
    describes (its section, ``well_from_dict``; None: vertical, no friction)."""
    keys = tuple(f.name for f in fields(StringGeometry) if f.name != "well")
    given = _section(name, {"string": string}, "string", keys, required=True, need=())
    sections = given.pop("sections", None)
    if sections is not None:
        if not isinstance(sections, list) or not sections:
            got = "an empty list" if sections == [] else f"{type(sections).__name__}"
            raise ParameterError(f"preset {name!r}: string.sections is {got}: expected a "
                                 "list of at least two sections (mappings: the pipe's, then "
                                 "the BHA's), top first")
        parts = []
        for i, section in enumerate(sections):
            where = f"string.sections[{i}]"
            row = _section(name, {where: section}, where, _SECTION_KEYS, required=True,
                           need=_SECTION_KEYS[:3])
            try:
                parts.append(StringSection(**row))
            except ParameterError as exc:
                raise ParameterError(f"preset {name!r}: {where}: {exc}") from None
        given["sections"] = tuple(parts)
    if well is not None:
        given["well"] = well_from_dict(name, well)
    try:
        return StringGeometry(**given)
    except ParameterError as exc:
        raise ParameterError(f"preset {name!r}: string: {exc}") from None


def _commissioning(name: str, value: object) -> tuple[tuple[str, tuple[tuple[str, float],
                                                                        ...]], ...]:
    """The preset's ``commissioning`` section: ``{law: {gain: value}}``, each value a finite
    number (which law and gains, and their ranges: ``control.reference.check_commissioning``,
    wherever reference gains are computed)."""
    if value is None:                     # absent, or the key with nothing under it
        return ()
    if not isinstance(value, dict):
        raise ParameterError(f"preset {name!r}: commissioning is {type(value).__name__}: "
                             "expected a mapping of law names to mappings of gains, e.g. "
                             "{z_torque: {speed_lowpass_hz: 4.5}}")
    out = []
    for law, gains in value.items():
        if not isinstance(gains, dict) or not gains:
            got = "empty" if gains is None or gains == {} else type(gains).__name__
            raise ParameterError(f"preset {name!r}: commissioning.{law} is {got}: expected "
                                 "a mapping of gain names to numbers, e.g. {speed_lowpass_hz: "
                                 "4.5}")
        try:
            out.append((str(law), tuple((str(k), check_number(f"commissioning.{law}.{k}", v,
                                                              low=None))
                                        for k, v in gains.items())))
        except ParameterError as exc:
            raise ParameterError(f"preset {name!r}: {exc}") from None
    return tuple(out)


def _string_model(name: str, value: object, string: StringGeometry | None) -> str:
    """The preset's ``string_model``, checked; ``distributed`` needs the string geometry."""
    try:
        model = check_string_model(value)
    except ParameterError as exc:
        raise ParameterError(f"preset {name!r}: {exc}") from None
    if model == "distributed" and string is None:
        raise ParameterError(f"preset {name!r}: string_model = 'distributed' needs a 'string' "
                             "section (pipe geometry); a 'lumped' section has none")
    return model


def _section(name: str, data: dict, key: str, allowed: tuple[str, ...], *, required: bool,
             need: tuple[str, ...] | None = None) -> dict:
    section = data.get(key)
    if section is None:
        if required:
            raise ParameterError(f"preset {name!r}: missing section {key!r}")
        return {}
    if not isinstance(section, dict):
        raise ParameterError(f"preset {name!r}: section {key!r} must be a mapping")
    unknown = set(section) - set(allowed)
    if unknown:
        raise ParameterError(f"preset {name!r}: unknown key(s) {sorted(unknown)} in {key!r}; "
                             f"expected {', '.join(allowed)}")
    missing = [k for k in (allowed if need is None else need) if k not in section]
    if missing:
        raise ParameterError(f"preset {name!r}: missing key(s) {missing} in {key!r}")
    return dict(section)
