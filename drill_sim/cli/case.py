"""The model options ``simulate`` and ``stability`` share, resolved into one ``Case``.

Two modes: SI (``--preset`` with ``--rpm`` and ``--wob-kn`` or ``--hook-load-kn``, times in
seconds) and dimensionless (``--groups`` with ``--w0`` and ``--omega0``, times in units of t*).
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass

from ..core import RPM, Groups, Preset, load_preset, preset_names
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


def add_model_arguments(p: argparse.ArgumentParser) -> None:
    """The options of both modes; ``resolve_case`` refuses a mix of them."""
    g = p.add_argument_group("SI mode")
    g.add_argument("--preset", default=None,
                   help=f"shipped preset ({', '.join(preset_names())}) or preset YAML file; "
                        "default base")
    g.add_argument("--rpm", type=float, help="top-drive speed [rpm]; default: the preset's")
    load = g.add_mutually_exclusive_group()
    load.add_argument("--wob-kn", type=float,
                      help="available weight on bit W0 = W_s - H0 [kN]; default: the preset's")
    load.add_argument("--hook-load-kn", type=float, help="hook load H0 [kN]")
    d = p.add_argument_group("dimensionless mode")
    d.add_argument("--groups", help="n=4,psi=13.73,lambda=6.84,beta=0.36")
    d.add_argument("--w0", type=float, help="available weight W0/F* [-]")
    d.add_argument("--omega0", type=float, help="top-drive speed Omega0 t* [-]")


def parse_groups(text: str) -> Groups:
    values: dict[str, str] = {}
    for item in text.split(","):
        key, sep, value = item.partition("=")
        if not sep:
            raise UsageError(f"--groups: {item!r} is not key=value; expected "
                             "n=...,psi=...,lambda=...,beta=...")
        values[key.strip()] = value.strip()
    expected = {"n", "psi", "lambda", "beta"}
    if set(values) != expected:
        raise UsageError(f"--groups: got keys {sorted(values)}, expected exactly "
                         "n, psi, lambda, beta")
    try:
        numbers = {k: float(v) for k, v in values.items()}
    except ValueError as exc:
        raise UsageError(f"--groups: {exc}") from None
    return Groups(n=numbers["n"], psi=numbers["psi"], lam=numbers["lambda"], beta=numbers["beta"])


def resolve_case(args: argparse.Namespace) -> Case:
    if args.groups is not None:
        si_given = [o for o in ("preset", "rpm", "wob_kn", "hook_load_kn")
                    if getattr(args, o) is not None]
        if si_given:
            raise UsageError(f"--groups cannot be combined with --{si_given[0].replace('_', '-')}")
        if args.w0 is None or args.omega0 is None:
            raise UsageError("--groups needs --w0 and --omega0")
        groups = parse_groups(args.groups)
        return Case(groups, finite("--w0", args.w0), finite("--omega0", args.omega0), None)
    if args.w0 is not None or args.omega0 is not None:
        raise UsageError("--w0 and --omega0 go with --groups; in SI mode use --rpm and --wob-kn")
    preset = load_preset(args.preset or "base")
    rig = preset.rig
    rpm = preset.top_drive_speed_rpm if args.rpm is None else finite("--rpm", args.rpm)
    if rpm < 0:
        raise UsageError(f"--rpm = {rpm:g} is negative; expected a top-drive speed >= 0 rpm")
    if args.hook_load_kn is not None:
        hook_n = 1e3 * finite("--hook-load-kn", args.hook_load_kn)
        if hook_n < 0:
            raise UsageError(f"--hook-load-kn = {args.hook_load_kn:g} is negative; expected >= 0")
    else:
        wob_kn = preset.weight_on_bit_kn if args.wob_kn is None else finite("--wob-kn",
                                                                            args.wob_kn)
        hook_n = rig.submerged_weight_n - 1e3 * wob_kn
        if hook_n < 0:
            raise UsageError(f"--wob-kn = {wob_kn:g} exceeds the string's submerged weight "
                             f"{rig.submerged_weight_n / 1e3:.1f} kN")
    sc = rig.scales
    w0 = (rig.submerged_weight_n - hook_n) / sc.force_n
    return Case(rig.groups, w0, rpm * RPM * sc.time_s, preset)


def finite(name: str, value: float) -> float:
    if not math.isfinite(value):
        raise UsageError(f"{name} = {value} is not finite; expected a finite number")
    return value


def positive(name: str, value: float | None, default: float) -> float:
    """``value`` checked finite and > 0, or ``default`` when the option was not given."""
    if value is None:
        return default
    if not math.isfinite(value) or value <= 0:
        raise UsageError(f"{name} = {value} is out of range; expected a finite number > 0")
    return value
