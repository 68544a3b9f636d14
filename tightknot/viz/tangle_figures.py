"""Figures of a pulled tangle: the pulling force against the end-to-end distance."""

from __future__ import annotations

import os
from collections.abc import Sequence

from tightknot.viz.figures import COLORS, plt, save_png_atomic


def plot_force_extension(
    end_distance_m: Sequence[float], force_N: Sequence[float], phases: Sequence[str],
    path: str | os.PathLike[str], title: str, diameter: float | None = None,
) -> None:
    """The pulling force F [N] against the end-to-end distance d of a tangle's grips,
    one marker style per load phase ("relax", "pull", "force"), in mm (or in D0 when the
    rod ``diameter`` [m] is given)."""
    if not (len(end_distance_m) == len(force_N) == len(phases)) or not force_N:
        raise ValueError("end_distance_m, force_N and phases must be non-empty and of one "
                         "length")
    scale, unit = (1.0 / diameter, r"$d/D_0$") if diameter else (1e3, "d [mm]")
    fig, ax = plt.subplots(figsize=(6, 4))
    d = [v * scale for v in end_distance_m]
    ax.plot(d, force_N, color="0.7", linewidth=0.8, zorder=0)
    for k, phase in enumerate(dict.fromkeys(phases)):
        idx = [i for i, p in enumerate(phases) if p == phase]
        ax.plot([d[i] for i in idx], [force_N[i] for i in idx], "o", ms=4,
                color=COLORS[k % len(COLORS)], label=phase)
    ax.set_xlabel(f"end-to-end distance {unit}")
    ax.set_ylabel("pulling force F [N]")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left")
    save_png_atomic(fig, path)
