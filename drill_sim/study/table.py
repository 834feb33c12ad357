"""A map point's row: the window metrics of one run as CSV columns, SI or dimensionless.

Definitions (over the metrics window):

- ``ssi``: stick-slip severity index (Omega_max - Omega_min) / (2 mean Omega) [-], >= 1 when
  the bit stops; ``stick_fraction``, ``bounce_fraction``: shares of the window stuck (Omega = 0
  in contact) and off bottom [-].
- ``speed_drop``: (Omega0 - min Omega) / Omega0 [-], the measure of Aarsnes and van de Wouw's
  maps: 0 for steady rotation, 1 when the bit stops.
- ``mse``: mechanical specific energy (Teale), the work spent per volume of rock [Pa]:
  MSE = W/A + 2 pi N T / (A ROP), with A = pi a^2 the hole's area, W the mean WOB, N the
  top-drive speed [rev/s] (2 pi N = Omega0), T the mean surface torque and ROP the mean rate
  of penetration. Undefined (NaN) when the bit does not advance. In groups mode the thrust term
  needs a and L*, which the groups do not fix, so ``mse_rotary`` is the rotary term alone,
  Omega0 T / (A ROP), in units of the intrinsic specific energy epsilon: omega0 t / (2 pi v).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..core import RPM, Metrics, RigParameters


@dataclass(frozen=True)
class Column:
    """One metric: its name for ``--metric``, its CSV column and unit in each mode, and how the
    plot shows it in SI mode (``scale`` times the SI value, in ``display_unit``)."""

    name: str
    si: str
    si_unit: str
    groups: str
    groups_unit: str
    scale: float = 1.0
    display_unit: str = "-"

    def column(self, si: bool) -> str:
        return self.si if si else self.groups

    def unit(self, si: bool) -> str:
        return self.si_unit if si else self.groups_unit


METRICS = (
    Column("ssi", "ssi", "-", "ssi", "-"),
    Column("stick_fraction", "stick_fraction", "-", "stick_fraction", "-"),
    Column("bounce_fraction", "bounce_fraction", "-", "bounce_fraction", "-"),
    Column("speed_drop", "speed_drop", "-", "speed_drop", "-"),
    Column("min_bit_speed", "min_bit_speed_rad_s", "rad/s", "min_bit_speed", "1/t*",
           1 / RPM, "rpm"),
    Column("max_bit_speed", "max_bit_speed_rad_s", "rad/s", "max_bit_speed", "1/t*",
           1 / RPM, "rpm"),
    Column("mean_bit_speed", "mean_bit_speed_rad_s", "rad/s", "mean_bit_speed", "1/t*",
           1 / RPM, "rpm"),
    Column("mean_rop", "mean_rop_m_s", "m/s", "mean_rop", "L*/t*", 3600.0, "m/h"),
    Column("mean_wob", "mean_wob_n", "N", "mean_wob", "F*", 1e-3, "kN"),
    Column("mean_tob", "mean_tob_nm", "N m", "mean_tob", "C", 1e-3, "kN m"),
    Column("mean_surface_torque", "mean_surface_torque_nm", "N m", "mean_surface_torque", "C",
           1e-3, "kN m"),
    Column("mse", "mse_pa", "Pa", "mse_rotary", "epsilon", 1e-6, "MPa"),
)
METRIC_NAMES = tuple(c.name for c in METRICS)


def metric_units(si: bool) -> dict[str, str]:
    """CSV column -> unit of every metric in the mode."""
    return {c.column(si): c.unit(si) for c in METRICS}


def metric_row(m: Metrics, omega0: float, rig: RigParameters | None) -> dict[str, float]:
    """The metrics of one point as CSV columns; ``omega0`` is Omega0 t*; ``rig`` None: groups
    mode (dimensionless columns)."""
    drop = (omega0 - m.min_bit_speed) / omega0 if omega0 > 0 else math.nan
    rotary = omega0 * m.mean_surface_torque / (2.0 * math.pi * m.mean_rop) \
        if m.mean_rop > 0 else math.nan            # in units of epsilon
    dimensionless = {"ssi": m.ssi, "stick_fraction": m.stick_fraction,
                     "bounce_fraction": m.bounce_fraction, "speed_drop": drop,
                     "min_bit_speed": m.min_bit_speed, "max_bit_speed": m.max_bit_speed,
                     "mean_bit_speed": m.mean_bit_speed, "mean_rop": m.mean_rop,
                     "mean_wob": m.mean_wob, "mean_tob": m.mean_tob,
                     "mean_surface_torque": m.mean_surface_torque, "mse": rotary}
    if rig is None:
        return {c.groups: float(dimensionless[c.name]) for c in METRICS}
    si = m.to_si(rig.scales)
    area = math.pi * rig.bit_radius_m ** 2
    thrust = si["mean_wob_n"] / area
    mse = thrust + rotary * rig.intrinsic_specific_energy_pa if m.mean_rop > 0 else math.nan
    values = {"ssi": si["ssi"], "stick_fraction": si["stick_fraction"],
              "bounce_fraction": si["bounce_fraction"], "speed_drop": drop,
              "min_bit_speed": si["min_bit_speed_rad_s"],
              "max_bit_speed": si["max_bit_speed_rad_s"],
              "mean_bit_speed": si["mean_bit_speed_rad_s"], "mean_rop": si["mean_rop_m_s"],
              "mean_wob": si["mean_wob_n"], "mean_tob": si["mean_tob_nm"],
              "mean_surface_torque": si["mean_surface_torque_nm"], "mse": mse}
    return {c.si: float(values[c.name]) for c in METRICS}
