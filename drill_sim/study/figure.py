"""The map's figure: filled contours of one metric over the two swept quantities, the stick-slip
boundary, and the lines of the linear theory."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .theory import TheoryLine


def plot_map(path: str | Path, x: np.ndarray, y: np.ndarray, values: np.ndarray,
             stick: np.ndarray, *, x_label: str, y_label: str, metric_label: str,
             fine_x: np.ndarray, fine_y: np.ndarray, lines: Sequence[TheoryLine],
             log: bool, title: str, fraction: bool = False) -> None:
    """Write the figure to ``path`` (format from the extension).

    ``values`` and ``stick`` are (len(x), len(y)) arrays: the metric and whether the bit stuck
    at each grid point (NaN values are left blank); each line's field is (len(fine_x),
    len(fine_y)) and is drawn where it crosses zero. ``log``: logarithmic axes.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.ticker import MaxNLocator

    fig, ax = plt.subplots(figsize=(7.2, 6.0), constrained_layout=True)
    z = np.ma.masked_invalid(np.asarray(values, dtype=float).T)
    handles = []
    if z.count() > 0:
        low, high = float(z.min()), float(z.max())
        if 0.0 <= low and high <= 1.0 and fraction:
            levels = np.linspace(0.0, 1.0, 11)
        elif high > low:
            levels = MaxNLocator(12).tick_values(low, high)
        else:
            levels = np.array([low - 0.5, low + 0.5])
        filled = ax.contourf(x, y, z, levels=levels, cmap="viridis", extend="neither")
        fig.colorbar(filled, ax=ax, label=metric_label)
    else:
        ax.text(0.5, 0.5, f"{metric_label}: undefined at every point", ha="center",
                transform=ax.transAxes)
    gx, gy = np.meshgrid(x, y)
    ax.plot(gx.ravel(), gy.ravel(), ".", ms=1.5, color="0.6", zorder=2)
    indicator = np.asarray(stick, dtype=float).T
    if 0.0 < indicator.mean() < 1.0:
        ax.contour(x, y, indicator, levels=[0.5], colors="red", linewidths=2.0)
        handles.append(Line2D([], [], color="red", lw=2.0,
                              label="stick-slip boundary (stick fraction > 0 inside)"))
    elif indicator.mean() == 1.0:
        handles.append(Line2D([], [], ls="", label="stick-slip at every point"))
    for line in lines:
        ax.contour(fine_x, fine_y, np.ma.masked_invalid(line.field.T), levels=[0.0],
                   colors=line.color, linestyles=line.style, linewidths=1.4)
        handles.append(Line2D([], [], color=line.color, ls=line.style, lw=1.4,
                              label=line.label))
    if log:
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set_xlabel(x_label)
    ax.set_ylabel(y_label)
    ax.set_title(title, fontsize=10)
    if handles:
        legend = ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.11),
                           ncol=2, fontsize=7, frameon=True)
        legend.get_frame().set_facecolor("0.45")
        for text in legend.get_texts():
            text.set_color("white")
    fig.savefig(path, dpi=100)
    plt.close(fig)
