"""A rig session as the node runs it, without ROS: its settings, its initial state, which
commands it accepts and how run-time parameter changes reach the rig. The node and the
re-simulation of a recorded session (``drill_sim bag resim``) share these rules, so the
re-run does exactly what the node did.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields

from .parameters import ParameterError, RigParameters, StringGeometry
from .rig import Rig

COMMAND_FRAMES = ("", "top_drive")        # frame_id accepted on commands
RIG_FIELDS = tuple(f.name for f in fields(RigParameters))


def rig_parameters(values: dict[str, object]) -> RigParameters:
    """RigParameters from parameter values (raises ParameterError naming a bad one)."""
    return RigParameters(**{name: values[name] for name in RIG_FIELDS})


def key_figures(params: RigParameters) -> dict[str, float]:
    """The rig's key figures in SI and its dimensionless groups (msg_docs/node.md): the string's
    submerged weight W_s, the time scale t* = sqrt(I/C), the natural torsional frequency
    1/(2 pi t*) (string on the BHA), the axial one sqrt(n a zeta eps / M)/(2 pi) (the BHA on the
    cutting contact, the roots s^2 + n psi = 0 of the axial factor of Delta(s)), the force and
    length scales F*, L*, the wear-flat weight a l sigma below which the bit cannot cut, and
    n, psi, lambda, beta (stick-slip needs beta < 1)."""
    sc, g = params.scales, params.groups
    return {
        "submerged_weight_n": params.submerged_weight_n,
        "t_star_s": sc.time_s,
        "torsional_frequency_hz": 1.0 / (2.0 * math.pi * sc.time_s),
        "axial_frequency_hz": math.sqrt(g.n * g.psi) / (2.0 * math.pi * sc.time_s),
        "force_scale_n": sc.force_n,
        "length_scale_m": sc.length_m,
        "friction_weight_n": params.friction_weight_n,
        "n": float(g.n), "psi": g.psi, "lambda": g.lam, "beta": g.beta,
    }


def figures_line(params: RigParameters) -> str:
    """The key figures in one line, for a log or a terminal."""
    f = key_figures(params)
    return (f"W_s {f['submerged_weight_n'] / 1e3:.0f} kN, t* {f['t_star_s']:.3f} s, "
            f"torsional {f['torsional_frequency_hz']:.3f} Hz "
            f"(period {1 / f['torsional_frequency_hz']:.2f} s), axial "
            f"{f['axial_frequency_hz']:.2f} Hz, F* {f['force_scale_n'] / 1e3:.1f} kN, "
            f"L* {f['length_scale_m'] * 1e3:.2f} mm, wear-flat weight "
            f"{f['friction_weight_n'] / 1e3:.0f} kN; n {f['n']:.0f}, psi {f['psi']:.3g}, "
            f"lambda {f['lambda']:.3g}, beta {f['beta']:.3g}")


def make_rig(p: dict[str, object], geometry: StringGeometry | None = None) -> Rig:
    """The rig of a session's parameters, not yet started. ``string_model`` (absent: lumped,
    as in sessions recorded before it existed) ``distributed`` needs ``geometry``, the
    preset's pipe (the node's) or the one a bag's ``string`` record kept (``bag resim``)."""
    return Rig(rig_parameters(p), dt_s=p["dt_s"], stick_window_s=p["stick_slip_window_s"],
               hoist_speed_limit_m_s=p["hoist_speed_limit_m_s"],
               string_model=p.get("string_model", "lumped"), geometry=geometry)


def geometry_record(geometry: StringGeometry) -> dict[str, str]:
    """The pipe geometry as a bag's ``string`` metadata record (field -> exact text)."""
    return {f.name: repr(float(getattr(geometry, f.name))) for f in fields(StringGeometry)}


def geometry_from_record(record: dict[str, str]) -> StringGeometry:
    """The geometry ``geometry_record`` wrote (ParameterError if it is not one)."""
    names = {f.name for f in fields(StringGeometry)}
    try:
        return StringGeometry(**{k: float(v) for k, v in record.items() if k in names})
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"string record {record!r}: not a pipe geometry ({exc})") from None


def start(rig: Rig, p: dict[str, object]) -> None:
    """Put the rig in the session's initial state (at start and on reset)."""
    speed = p["initial_top_drive_speed_rad_s"]
    hook = rig.params.submerged_weight_n - p["initial_weight_on_bit_n"]
    if hook < 0:
        raise ParameterError(f"initial_weight_on_bit_n = {p['initial_weight_on_bit_n']:g} "
                             f"exceeds the string's submerged weight "
                             f"{rig.params.submerged_weight_n:g} N")
    if p["initial_state"] == "steady":
        rig.start_steady(speed, hook)
    else:
        rig.start_at_rest(p["initial_gap_m"])


@dataclass(frozen=True)
class CommandRule:
    """Which field of a command message carries the command, and the parameter that limits it.

    The commands are TwistStamped/WrenchStamped messages, taken as their six float64 in message
    order (linear or force x, y, z, then angular or torque x, y, z); ``index`` is the field's
    place among them, ``slot`` the argument of ``Rig.command`` it sets (0 speed, 1 hook load)."""

    what: str            # for refusals
    field: str           # message field path
    index: int
    slot: int
    limit: str           # parameter: the largest value accepted
    unit: str


COMMANDS = {
    "top_drive": CommandRule("top-drive speed", "twist.angular.z", 5, 0,
                             "max_top_drive_speed_rad_s", "rad/s"),
    "hook_load": CommandRule("hook load", "wrench.force.z", 2, 1, "max_hook_load_n", "N"),
}


def command_refusal(frame_id: str, value: float, high: float, what: str, unit: str
                    ) -> tuple[str, object, str] | None:
    """Why a command is refused, as (what, value, expected), or None if it is used: the frame
    must be one of COMMAND_FRAMES and the value finite in [0, high]."""
    if frame_id not in COMMAND_FRAMES:
        return f"{what} frame_id", frame_id, "'top_drive' or empty"
    if not (math.isfinite(value) and 0.0 <= value <= high):
        return f"{what} [{unit}]", value, f"a finite value in [0, {high:g}] {unit}"
    return None


def apply_command(rig: Rig, p: dict[str, object], name: str, frame_id: str,
                  six: Sequence[float]) -> tuple[str, object, str] | None:
    """Command ``name`` (a key of COMMANDS) arriving as ``six`` with ``frame_id``: held by the
    rig from now on if accepted (None), else the refusal as ``command_refusal`` gives it and the
    rig untouched. The node and the re-simulation of its bags both decide here."""
    rule = COMMANDS[name]
    value = six[rule.index]
    refusal = command_refusal(frame_id, value, p[rule.limit], f"{rule.what} {rule.field}",
                              rule.unit)
    if refusal is None:
        held = [rig.commanded_speed_rad_s, rig.commanded_hook_load_n]
        held[rule.slot] = value
        rig.command(*held)
    return refusal


def apply_changes(rig: Rig, old: dict[str, object], new: dict[str, object]) -> set[str]:
    """Bring the rig to the parameter values ``new`` (from ``old``); the names that changed.
    Raises ParameterError, leaving the rig as it was, if the new values are refused."""
    changed = {k for k in new if new[k] != old.get(k)}
    if changed & set(RIG_FIELDS):
        rig.replace_parameters(rig_parameters(new))
    if "stick_slip_window_s" in changed:
        rig.set_stick_window(new["stick_slip_window_s"])
    if "hoist_speed_limit_m_s" in changed:
        rig.set_hoist_speed_limit(new["hoist_speed_limit_m_s"])
    return changed


def parse_value(text: str) -> object:
    """A parameter value back from its recorded text (bool, int, float or str)."""
    if text in ("True", "False"):
        return text == "True"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text
