"""The lumped and the distributed string side by side on base at 60 rpm / 100 kN: bit speed,
surface torque and stick-slip period. Writes msg_docs/string_models.png and prints the numbers
quoted in msg_docs/model.md.

    python benchmarks/fig_string_models.py [OUT.png]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from drill_sim.core import DEFAULT_DT, RPM, Simulator, load_preset
from drill_sim.core.distributed import geometry_waves
from drill_sim.core.distributed_simulator import StringSimulator

LEAD_S, WINDOW_S, SHOWN_S = 60.0, 60.0, 15.0
INTERVAL_S = 0.005
T_STAR_S = load_preset("base").rig.scales.time_s


def run(model: str):
    """(time [s], bit speed [rpm], surface torque [kN m], stuck, metrics) over the window."""
    p = load_preset("base")
    sc, groups = p.rig.scales, p.rig.groups
    sim = Simulator(groups, DEFAULT_DT) if model == "lumped" else StringSimulator(
        groups, geometry_waves(p.rig, p.string, DEFAULT_DT))
    sim.start_steady(1e3 * p.weight_on_bit_kn / sc.force_n,
                     p.top_drive_speed_rad_s * sc.time_s, 1e-3)
    sim.run(LEAD_S / sc.time_s)
    sim.reset_window()
    tr = sim.run(WINDOW_S / sc.time_s, output_interval=INTERVAL_S / sc.time_s)
    time_s = tr.tau * sc.time_s
    return (time_s - time_s[0], tr.omega / sc.time_s / RPM,
            tr.ts * sc.stiffness_nm_per_rad / 1e3, tr.stuck, tr.metrics)


def stick_period_s(time_s: np.ndarray, stuck: np.ndarray) -> float:
    """Mean time between the starts of successive stick phases [s] (nan if fewer than two)."""
    onsets = time_s[1:][stuck[1:] & ~stuck[:-1]]
    return float(np.mean(np.diff(onsets))) if onsets.size > 1 else float("nan")


def main(out: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_speed, ax_torque) = plt.subplots(2, 1, figsize=(7.0, 4.6), sharex=True)
    for model, colour in (("lumped", "tab:blue"), ("distributed", "tab:red")):
        t, speed, torque, stuck, m = run(model)
        period = stick_period_s(t, stuck)
        label = f"{model}: stick {m.stick_fraction:.2f}, period {period:.2f} s"
        print(f"{model:11s} stick fraction {m.stick_fraction:.3f}, stick-slip period "
              f"{period:.3f} s, mean bit speed {m.mean_bit_speed / T_STAR_S / RPM:.2f} rpm, "
              f"max {np.max(speed):.1f} rpm, surface torque {np.min(torque):.2f} to "
              f"{np.max(torque):.2f} kN m")
        shown = t <= SHOWN_S
        ax_speed.plot(t[shown], speed[shown], color=colour, lw=0.9, label=label)
        ax_torque.plot(t[shown], torque[shown], color=colour, lw=0.9)
    ax_speed.axhline(60.0, color="0.5", lw=0.6, ls="--")
    ax_speed.set_ylim(top=1.4 * ax_speed.get_ylim()[1])
    ax_speed.set_ylabel("bit speed [rpm]")
    ax_speed.legend(loc="upper right", fontsize=8, frameon=False)
    ax_torque.set_ylabel("surface torque [kN m]")
    ax_torque.set_xlabel(f"time after {LEAD_S:g} s of drilling [s]")
    fig.suptitle("base, 60 rpm, 100 kN: lumped and distributed string", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    print(f"written {out} ({out.stat().st_size / 1e3:.0f} kB)")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else
         Path(__file__).resolve().parents[1] / "msg_docs" / "string_models.png")
