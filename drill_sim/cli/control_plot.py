"""The figure of ``drill_sim control``: bit speed and surface torque of each law on one scenario."""

from __future__ import annotations

from pathlib import Path

from ..control.evaluation import LoopResult, Scenario
from ..core import RPM


def plot_laws(path: str | Path, scenario: Scenario, results: list[LoopResult]) -> None:
    """Two panels against time: bit speed [rpm] and surface torque [kN m], one line per law;
    the metrics window shaded, the switch-on instant marked (before it: the drive's own loop)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(10, 6.5), constrained_layout=True)
    for r in results:
        s = r.series
        label = f"{r.law}: SSI {r.ssi:.2f}, stick {r.stick_fraction:.2f}"
        axes[0].plot(s["time_s"], s["bit_speed_rad_s"] / RPM, lw=0.7, label=label)
        axes[1].plot(s["time_s"], s["surface_torque_nm"] / 1e3, lw=0.7, label=r.law)
    for ax in axes:
        ax.axvspan(scenario.metrics_from_s, scenario.duration_s, color="0.9", zorder=0)
        if scenario.switch_on_s > 0.0:
            ax.axvline(scenario.switch_on_s, color="k", ls="--", lw=0.8)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("bit speed [rpm]")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title(f"drill_sim control: {scenario.name} (shaded: metrics window"
                      + (", dashed: controller switched on)" if scenario.switch_on_s else ")"))
    axes[1].set_ylabel("surface torque [kN m]")
    axes[1].set_xlabel("time [s]")
    fig.savefig(path, dpi=110)
    plt.close(fig)
