"""The model options ``simulate`` and ``stability`` share, resolved into one ``Case``.

Two modes: SI (``--preset`` with ``--rpm`` and ``--wob-kn`` or ``--hook-load-kn``, times in
seconds) and dimensionless (``--groups`` with ``--w0`` and ``--omega0``, times in units of t*).
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass

from ..core import RPM, Groups, Preset, load_preset, preset_names
from .checks import in_range, number
from .errors import UsageError


@dataclass(frozen=True)
class Case:
    """What to simulate, resolved from the arguments: groups, commands and unit scales."""

    groups: Groups
    w0: float
    omega0: float
    preset: Preset | None      # None in dimensionless mode

    @property
    def si(self) -> bool:
        return self.preset is not None


# The documented ranges of the model options (msg_docs/cli.md, "Limits").
RPM_MAX = 400.0           # top-drive speed [rpm]
OMEGA0_MAX = 50.0         # Omega0 t* [-]
W0_MAX = 1000.0           # |W0| / F* [-]
MAX_BLADES = 64           # n, as the core allows
PSI_RANGE = (0.01, 1000.0)
LAMBDA_RANGE = (0.0, 1000.0)
BETA_RANGE = (0.0, 10.0)


def add_model_arguments(p: argparse.ArgumentParser) -> None:
    """The options of both modes; ``resolve_case`` refuses a mix of them."""
    g = p.add_argument_group("SI mode")
    g.add_argument("--preset", default=None,
                   help=f"shipped preset ({', '.join(preset_names())}) or preset YAML file; "
                        "default base")
    g.add_argument("--rpm", type=number,
                   help=f"top-drive speed [rpm], 0 to {RPM_MAX:g}; default: the preset's")
    load = g.add_mutually_exclusive_group()
    load.add_argument("--wob-kn", type=number,
                      help="available weight on bit W0 = W_s - H0 [kN], -W_s to W_s; default: "
                           "the preset's")
    load.add_argument("--hook-load-kn", type=number, help="hook load H0 [kN], 0 to 2 W_s")
    d = p.add_argument_group("dimensionless mode")
    d.add_argument("--groups", help="n=4,psi=13.73,lambda=6.84,beta=0.36")
    d.add_argument("--w0", type=number, help=f"available weight W0/F* [-], -{W0_MAX:g} to "
                                             f"{W0_MAX:g}")
    d.add_argument("--omega0", type=number,
                   help=f"top-drive speed Omega0 t* [-], 0 to {OMEGA0_MAX:g}")


def parse_groups(text: str) -> Groups:
    """``n=4,psi=13.73,lambda=6.84,beta=0.36`` as Groups, each within its documented range."""
    values: dict[str, str] = {}
    for item in text.split(","):
        key, sep, value = item.partition("=")
        if not sep:
            raise UsageError(f"--groups {text}: {item!r} is not key=value; expected "
                             "n=...,psi=...,lambda=...,beta=...")
        values[key.strip()] = value.strip()
    expected = {"n", "psi", "lambda", "beta"}
    if set(values) != expected:
        raise UsageError(f"--groups {text}: got keys {', '.join(sorted(values))}; expected "
                         "exactly n, psi, lambda, beta")
    numbers = {}
    for key, value in values.items():
        try:
            numbers[key] = float(value)
        except ValueError:
            raise UsageError(f"--groups {text}: {key} = {value!r} is not a number; expected "
                             "a decimal number") from None
    n = numbers["n"]
    if not math.isfinite(n) or n != int(n) or not 1 <= n <= MAX_BLADES:
        raise UsageError(f"--groups {text}: n (blade count) = {values['n']} is out of range; "
                         f"expected a whole number 1 to {MAX_BLADES}")
    for key, (low, high) in (("psi", PSI_RANGE), ("lambda", LAMBDA_RANGE), ("beta", BETA_RANGE)):
        if not low <= numbers[key] <= high:
            raise UsageError(f"--groups {text}: {key} = {values[key]} is out of range; expected "
                             f"{low:g} to {high:g}")
    return Groups(n=numbers["n"], psi=numbers["psi"], lam=numbers["lambda"], beta=numbers["beta"])


def resolve_case(args: argparse.Namespace) -> Case:
    """The Case the model options describe, every value within its documented range."""
    if args.groups is not None:
        si_given = [o for o in ("preset", "rpm", "wob_kn", "hook_load_kn")
                    if getattr(args, o) is not None]
        if si_given:
            raise UsageError(f"--groups cannot be combined with --{si_given[0].replace('_', '-')}")
        if args.w0 is None or args.omega0 is None:
            raise UsageError("--groups needs --w0 and --omega0")
        groups = parse_groups(args.groups)
        w0 = in_range("--w0", args.w0, -W0_MAX, W0_MAX, what="an available weight W0/F*")
        omega0 = in_range("--omega0", args.omega0, 0.0, OMEGA0_MAX,
                          what="a top-drive speed Omega0 t*")
        return Case(groups, w0, omega0, None)
    if args.w0 is not None or args.omega0 is not None:
        raise UsageError("--w0 and --omega0 go with --groups; in SI mode use --rpm and --wob-kn")
    preset = load_preset(args.preset or "base")
    rig = preset.rig
    weight_kn = rig.submerged_weight_n / 1e3
    rpm = in_range("--rpm" if args.rpm is not None else f"preset {preset.name!r} "
                   "commands.top_drive_speed_rpm",
                   preset.top_drive_speed_rpm if args.rpm is None else args.rpm,
                   0.0, RPM_MAX, unit="rpm", what="a top-drive speed")
    if args.hook_load_kn is not None:
        hook_kn = in_range("--hook-load-kn", args.hook_load_kn, 0.0, 2.0 * weight_kn, unit="kN",
                           what=f"a hook load from 0 to twice the {preset.name} string's "
                                f"submerged weight W_s = {weight_kn:.1f} kN:")
        wob_kn = wob_from_hook_load_kn(preset, hook_kn)
    elif args.wob_kn is not None:
        wob_kn = in_range("--wob-kn", args.wob_kn, -weight_kn, weight_kn, unit="kN",
                          what=f"an available weight within the {preset.name} string's "
                               f"submerged weight W_s = {weight_kn:.1f} kN:")
    else:
        wob_kn = in_range(f"preset {preset.name!r} commands.weight_on_bit_kn",
                          preset.weight_on_bit_kn, -weight_kn, weight_kn, unit="kN",
                          what=f"an available weight within the string's submerged weight "
                               f"W_s = {weight_kn:.1f} kN:")
    return si_case(preset, rpm, wob_kn)


def si_case(preset: Preset, rpm: float, wob_kn: float) -> Case:
    """The Case of ``preset`` at top-drive speed ``rpm`` [rpm] and available weight W0 ``wob_kn``
    [kN]: the one conversion ``simulate`` and every point of ``map`` use."""
    sc = preset.rig.scales
    return Case(preset.rig.groups, 1e3 * wob_kn / sc.force_n, rpm * RPM * sc.time_s, preset)


def wob_from_hook_load_kn(preset: Preset, hook_load_kn: float) -> float:
    """Available weight W0 = W_s - H0 [kN] of ``preset``'s string at hook load H0 [kN]."""
    return preset.rig.submerged_weight_n / 1e3 - hook_load_kn
