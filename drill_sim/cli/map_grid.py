"""The quantities ``drill_sim map`` can sweep, their values from the command line, and the grid
of points they make.

Each swept quantity is an option taking one value (held fixed), a comma list (``40,60,150``) or a
range ``start:stop:count`` (both ends included; evenly spaced, or geometrically with ``--log``).
The quantities with more than one value are the map's axes (at most two); a map has two axes,
filled up from the mode's defaults (top-drive speed, then weight) with single values. A new
quantity is one more ``Quantity`` and a line in ``Grid.case`` and ``Grid.dimensionless``.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass, replace

import numpy as np

from ..core import RPM, Groups, Preset, load_preset
from .case import (
    BETA_RANGE,
    LAMBDA_RANGE,
    OMEGA0_MAX,
    PSI_RANGE,
    RPM_MAX,
    W0_MAX,
    Case,
    parse_groups,
    si_case,
    wob_from_hook_load_kn,
)
from .checks import Number, in_range, whole
from .errors import UsageError

MAX_AXIS_POINTS = 1000
MAX_POINTS = 250_000
DEFAULT_RPM = "20:300:30"          # SI mode, when --rpm is not given [rpm]
DEFAULT_WOB_KN = "50:250:30"       # SI mode, when neither --wob-kn nor --hook-load-kn [kN]


@dataclass(frozen=True)
class Quantity:
    """A quantity a map can sweep: its option, CSV column, unit and axis label."""

    dest: str
    column: str
    unit: str
    label: str
    what: str          # for range errors: "a top-drive speed"
    si: bool
    symbol: str        # in titles: "Ω0"

    @property
    def option(self) -> str:
        return "--" + self.dest.replace("_", "-")


QUANTITIES = (
    Quantity("rpm", "top_drive_speed_rpm", "rpm", "top-drive speed Ω0 [rpm]",
             "a top-drive speed", True, "Ω0"),
    Quantity("wob_kn", "wob_kn", "kN", "available weight on bit W0 [kN]",
             "an available weight within the string's submerged weight W_s:", True, "W0"),
    Quantity("hook_load_kn", "hook_load_kn", "kN", "hook load H0 [kN]",
             "a hook load from 0 to twice the string's submerged weight W_s:", True, "H0"),
    Quantity("omega0", "omega0", "1/t*", "ω0 = Ω0 t* [-]", "a top-drive speed Omega0 t*", False,
             "ω0"),
    Quantity("w0", "w0", "F*", "w0 = W0/F* [-]", "an available weight W0/F*", False, "w0"),
    Quantity("psi", "psi", "-", "ψ [-]", "an inertia ratio psi", False, "ψ"),
    Quantity("lambda", "lambda", "-", "λ [-]", "a wear-flat weight lambda", False, "λ"),
    Quantity("beta", "beta", "-", "β [-]", "a friction ratio beta", False, "β"),
)
BY_DEST = {q.dest: q for q in QUANTITIES}


def add_quantity_arguments(parser: argparse.ArgumentParser) -> None:
    g = parser.add_argument_group("SI mode (each quantity: a value, a list a,b,c or a range "
                                  "start:stop:count)")
    g.add_argument("--preset", default=None,
                   help="shipped preset or preset YAML file; default base")
    g.add_argument("--rpm", help=f"top-drive speed [rpm], 0 to {RPM_MAX:g}; default {DEFAULT_RPM}")
    load = g.add_mutually_exclusive_group()
    load.add_argument("--wob-kn", help="available weight on bit W0 = W_s - H0 [kN], -W_s to W_s; "
                                       f"default {DEFAULT_WOB_KN} (up to W_s)")
    load.add_argument("--hook-load-kn", help="hook load H0 [kN], 0 to 2 W_s")
    d = parser.add_argument_group("dimensionless mode")
    d.add_argument("--groups", help="n=4,psi=13.73,lambda=6.84,beta=0.36")
    d.add_argument("--omega0", help=f"top-drive speed Omega0 t* [-], 0 to {OMEGA0_MAX:g} (needed)")
    d.add_argument("--w0", help=f"available weight W0/F* [-], -{W0_MAX:g} to {W0_MAX:g} (needed)")
    for name, (low, high) in (("psi", PSI_RANGE), ("lambda", LAMBDA_RANGE), ("beta", BETA_RANGE)):
        d.add_argument(f"--{name}", help=f"{name} [-], {low:g} to {high:g}; default: --groups'")
    parser.add_argument("--log", action="store_true",
                        help="ranges spaced geometrically, and the plot's axes logarithmic")


def parse_values(q: Quantity, text: str, low: float, high: float, log: bool) -> np.ndarray:
    """The sorted values of ``text`` for quantity ``q``, each within ``low``..``high``."""
    text = text.strip()

    def check(part: str) -> float:
        try:
            value = Number(part.strip())
        except ValueError:
            raise UsageError(f"{q.option} {text}: {part.strip()!r} is not a number; expected a "
                             "value, a list a,b,c or a range start:stop:count") from None
        try:
            value = in_range(q.option, value, low, high, unit=q.unit, what=q.what)
        except UsageError as exc:
            raise UsageError(f"{q.option} {text}: {part.strip()} is "
                             f"{str(exc).split(': ', 1)[1]}") from None
        if log and value <= 0:
            raise UsageError(f"{q.option} {text} with --log: {part.strip()} is not positive; "
                             "expected values > 0 on logarithmic axes")
        return value

    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise UsageError(f"{q.option} {text}: expected a range start:stop:count such as "
                             "20:300:30")
        start, stop = check(parts[0]), check(parts[1])
        try:
            count = int(parts[2])
        except ValueError:
            raise UsageError(f"{q.option} {text}: count {parts[2]!r} is not a whole number; "
                             "expected start:stop:count such as 20:300:30") from None
        whole(f"{q.option} {text}: count", count, 2, MAX_AXIS_POINTS)
        if not start < stop:
            raise UsageError(f"{q.option} {text}: start is not below stop; expected an "
                             "increasing range start:stop:count")
        values = np.geomspace(start, stop, count) if log else np.linspace(start, stop, count)
        return values
    values = np.array(sorted(check(p) for p in text.split(",")))
    if values.size > MAX_AXIS_POINTS:
        raise UsageError(f"{q.option}: {values.size} values; expected at most "
                         f"{MAX_AXIS_POINTS}")
    if np.any(np.diff(values) == 0):
        raise UsageError(f"{q.option} {text}: a value is repeated; expected distinct values")
    return values


@dataclass(frozen=True)
class Grid:
    """The map's points: every (x, y) of the two axes, the other quantities held at ``fixed``.
    Point p is (i, j) = divmod(p, len(y)): x outer, y inner."""

    preset: Preset | None        # SI mode; None in groups mode
    groups: Groups | None        # groups mode: the --groups given
    x: Quantity
    y: Quantity
    x_values: np.ndarray
    y_values: np.ndarray
    fixed: dict[str, float]

    @property
    def si(self) -> bool:
        return self.preset is not None

    @property
    def size(self) -> int:
        return self.x_values.size * self.y_values.size

    def values(self, point: int) -> dict[str, float]:
        """Every quantity's value at ``point``."""
        i, j = divmod(point, self.y_values.size)
        return {**self.fixed, self.x.dest: float(self.x_values[i]),
                self.y.dest: float(self.y_values[j])}

    def label(self, point: int) -> str:
        v = self.values(point)
        return ", ".join(f"{q.option} {v[q.dest]:g}" for q in (self.x, self.y))

    def case(self, point: int) -> Case:
        """The point's Case, by the conversion ``simulate`` uses."""
        v = self.values(point)
        if self.si:
            wob = v["wob_kn"] if "wob_kn" in v else wob_from_hook_load_kn(self.preset,
                                                                           v["hook_load_kn"])
            return si_case(self.preset, v["rpm"], wob)
        groups = replace(self.groups, psi=v["psi"], lam=v["lambda"], beta=v["beta"])
        return Case(groups, v["w0"], v["omega0"], None)

    def dimensionless(self, xs: np.ndarray, ys: np.ndarray) -> dict[str, np.ndarray]:
        """n, psi, lam, beta, w0 and omega0 on the grid ``xs`` x ``ys`` (index [i, j])."""
        gx, gy = np.meshgrid(xs, ys, indexing="ij")
        v = {**{k: np.full(gx.shape, val) for k, val in self.fixed.items()},
             self.x.dest: gx, self.y.dest: gy}
        if self.si:
            rig = self.preset.rig
            sc, g = rig.scales, rig.groups
            wob = v["wob_kn"] if "wob_kn" in v else rig.submerged_weight_n / 1e3 - v["hook_load_kn"]
            return {"n": g.n, "psi": np.full(gx.shape, g.psi), "lam": np.full(gx.shape, g.lam),
                    "beta": np.full(gx.shape, g.beta), "w0": 1e3 * wob / sc.force_n,
                    "omega0": v["rpm"] * RPM * sc.time_s}
        return {"n": self.groups.n, "psi": v["psi"], "lam": v["lambda"], "beta": v["beta"],
                "w0": v["w0"], "omega0": v["omega0"]}


def build_grid(args: argparse.Namespace) -> Grid:
    """The grid the quantity options describe, every value within its documented range."""
    if args.groups is not None:
        given = [o for o in ("preset", "rpm", "wob_kn", "hook_load_kn") if getattr(args, o)]
        if given:
            raise UsageError(f"--groups cannot be combined with --{given[0].replace('_', '-')}")
        if args.w0 is None or args.omega0 is None:
            raise UsageError("--groups needs --w0 and --omega0 (each a value, a list or a range "
                             "start:stop:count)")
        preset, groups = None, parse_groups(args.groups)
        texts = {"omega0": args.omega0, "w0": args.w0, "psi": args.psi,
                 "lambda": getattr(args, "lambda"), "beta": args.beta}
        defaults = {"psi": groups.psi, "lambda": groups.lam, "beta": groups.beta}
        limits = {"omega0": (0.0, OMEGA0_MAX), "w0": (-W0_MAX, W0_MAX), "psi": PSI_RANGE,
                  "lambda": LAMBDA_RANGE, "beta": BETA_RANGE}
        pair = ("omega0", "w0")
    else:
        dimensionless = [o for o in ("w0", "omega0", "psi", "lambda", "beta")
                         if getattr(args, o) is not None]
        if dimensionless:
            raise UsageError(f"--{dimensionless[0]} goes with --groups; in SI mode use --rpm and "
                             "--wob-kn")
        preset, groups = load_preset(args.preset or "base"), None
        weight_kn = preset.rig.submerged_weight_n / 1e3
        load = "hook_load_kn" if args.hook_load_kn is not None else "wob_kn"
        high = min(250.0, weight_kn)              # the default range, within W_s
        default_wob = DEFAULT_WOB_KN if high == 250.0 else f"{min(50.0, 0.2 * high):.6g}:" \
            f"{high:.6g}:30"
        texts = {"rpm": args.rpm or DEFAULT_RPM,
                 load: args.hook_load_kn if load == "hook_load_kn" else args.wob_kn or default_wob}
        defaults = {}
        limits = {"rpm": (0.0, RPM_MAX), "wob_kn": (-weight_kn, weight_kn),
                  "hook_load_kn": (0.0, 2.0 * weight_kn)}
        pair = ("rpm", load)
    values = {dest: parse_values(BY_DEST[dest], text, *limits[dest], args.log)
              if text is not None else np.array([defaults[dest]])
              for dest, text in texts.items()}
    swept = [d for d in values if values[d].size > 1]
    if len(swept) > 2:
        named = ", ".join(BY_DEST[d].option for d in swept)
        raise UsageError(f"{named}: {len(swept)} quantities have several values; expected at "
                         "most two swept quantities (the map's axes), the others single values")
    axes = swept + [d for d in pair if d not in swept][:2 - len(swept)]
    axes.sort(key=list(values).index)
    x, y = (BY_DEST[d] for d in axes)
    grid = Grid(preset, groups, x, y, values[x.dest], values[y.dest],
                {d: float(v[0]) for d, v in values.items() if d not in axes})
    if grid.size > MAX_POINTS:
        raise UsageError(f"{x.option} and {y.option} make {grid.size:,} points; expected at "
                         f"most {MAX_POINTS:,}")
    return grid
