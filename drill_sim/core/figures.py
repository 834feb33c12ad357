"""A rig's key figures in SI and its dimensionless groups, for logs, bags and terminals."""

from __future__ import annotations

import math

from .parameters import RigParameters


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


def string_first_mode(rig) -> str:
    """The distributed string's first torsional mode off bottom, top held, damped (exact pipe:
    ``stability_distributed.string_modes``), in words: "first torsional mode 0.555 Hz
    (damping ratio 4.9 %)"."""
    from .distributed import geometry_waves
    from .simulator import DEFAULT_DT
    from .stability_distributed import string_modes
    from .top_drive import DriveGroups
    params = rig.params
    waves = geometry_waves(params, rig.geometry, DEFAULT_DT, continuous=True)
    modes = string_modes(waves, params.groups.psi, DriveGroups(), count=1)
    if not modes.torsional:
        return "first torsional mode not found"
    m = modes.torsional[0]
    return (f"first torsional mode {m.frequency / (2.0 * math.pi * params.scales.time_s):.3f} "
            f"Hz (damping ratio {100 * m.damping_ratio:.1f} %)")
