"""Figures: bit speed against time (like RGD 2007, Figure 2) with weight and torque on bit."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def plot_time_series(path: str | Path, time: np.ndarray, bit_speed: np.ndarray,
                     top_drive_speed: np.ndarray, wob: np.ndarray, tob: np.ndarray,
                     surface_torque: np.ndarray, stuck: np.ndarray, *, units: dict[str, str],
                     title: str, motor_torque: np.ndarray | None = None,
                     marks: dict[float, str] | None = None,
                     speed_set: np.ndarray | None = None,
                     torque_limits: tuple[float, float] | None = None) -> None:
    """Write a three-panel PNG; ``units`` labels the axes (time, speed, force, torque);
    ``motor_torque``, when given, is drawn with the torques (the top drive's motor);
    ``marks``: time -> label, drawn as dashed vertical lines (a controller switched on);
    ``speed_set``: the speed set-point, drawn with the speeds; ``torque_limits``: the drive's
    (min, max) motor torque, which adds a fourth panel: the motor torque against them."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    drive = motor_torque is not None and torque_limits is not None
    fig, axes = plt.subplots(4 if drive else 3, 1, sharex=True,
                             figsize=(10, 9.5 if drive else 7.5), constrained_layout=True)
    ax = axes[0]
    ax.plot(time, bit_speed, lw=0.8, label="bit")
    ax.plot(time, top_drive_speed, "k--", lw=0.8, label="top drive")
    if speed_set is not None:
        ax.plot(time, speed_set, color="tab:red", lw=1.0, label="set-point")
    if np.any(stuck):
        ax.fill_between(time, 0, 1, where=stuck, color="tab:red", alpha=0.15,
                        transform=ax.get_xaxis_transform(), label="stuck", step="mid")
    ax.set_ylabel(f"speed [{units['speed']}]")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(title)
    axes[1].plot(time, wob, lw=0.8, color="tab:green")
    axes[1].set_ylabel(f"WOB [{units['force']}]")
    axes[2].plot(time, tob, lw=0.8, color="tab:orange", label="on bit")
    axes[2].plot(time, surface_torque, lw=0.8, color="tab:purple", label="surface (string)")
    if motor_torque is not None and not drive:
        axes[2].plot(time, motor_torque, lw=0.8, color="tab:gray", label="top-drive motor")
    axes[2].set_ylabel(f"torque [{units['torque']}]")
    axes[2].legend(loc="upper right", fontsize=8)
    if drive:
        axes[3].plot(time, motor_torque, lw=0.8, color="tab:gray", label="top-drive motor")
        for limit in torque_limits:
            axes[3].axhline(limit, color="tab:red", ls=":", lw=1.0)
        axes[3].plot([], [], color="tab:red", ls=":", label="drive's limits")
        axes[3].set_ylabel(f"motor torque [{units['torque']}]")
        axes[3].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel(f"time [{units['time']}]")
    for a in axes:
        a.grid(alpha=0.3)
        for at in (marks or {}):
            a.axvline(at, color="k", ls="--", lw=0.9)
    for k, (at, label) in enumerate(sorted((marks or {}).items())):
        axes[0].annotate(label, (at, 1.0), xycoords=("data", "axes fraction"),
                         xytext=(4, -12 - 11 * (k % 3)), textcoords="offset points", fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_rig_series(path: str | Path, series, title: str,
                    motor_torque_nm: np.ndarray | None = None,
                    marks: dict[float, str] | None = None,
                    speed_set_rad_s: np.ndarray | None = None,
                    torque_limits_nm: tuple[float, float] | None = None) -> None:
    """The rig's SI series (drill_sim.bag.series.RigSeries) in rpm, kN and kN m, with the
    motor torque [N m] at its samples, the speed set-point [rad/s] and the drive's motor
    torque limits [N m] when given."""
    from ..core import RPM
    t = series.time_s - series.time_s[0]
    plot_time_series(path, t, series.bit_speed_rad_s / RPM, series.top_drive_speed_rad_s / RPM,
                     series.wob_n / 1e3, series.tob_nm / 1e3, series.surface_torque_nm / 1e3,
                     series.stuck,
                     units={"time": "s", "speed": "rpm", "force": "kN", "torque": "kN m"},
                     title=title,
                     motor_torque=None if motor_torque_nm is None else motor_torque_nm / 1e3,
                     marks=marks,
                     speed_set=None if speed_set_rad_s is None else speed_set_rad_s / RPM,
                     torque_limits=None if torque_limits_nm is None else
                     (torque_limits_nm[0] / 1e3, torque_limits_nm[1] / 1e3))
