"""Figures of knot measurements (matplotlib Agg, PNG at 150 dpi, written atomically).

Every function takes the dicts returned by :func:`tightknot.knots.measure.analyze_centerline`
(plus optional per-vertex arrays) and writes one PNG. Axes carry the non-dimensional names of
Johanns et al. 2021 (s, sigma, rho, z, kappa D0, L_c, A/A0). Colours are fixed: elastic or
measured knots in blue/orange, the ideal knot in black dashes.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")  # files only; never needs a display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

DPI = 150
COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728")
IDEAL_STYLE = {"color": "black", "linestyle": "--", "linewidth": 1.0, "label": "ideal"}


def save_png_atomic(fig: Any, path: str | os.PathLike[str]) -> None:
    """Save ``fig`` as PNG to a temporary name beside ``path``, then rename (atomic)."""
    target = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    # mkstemp creates 0600 files; give the figure the usual permissions of the umask (as
    # tightknot.atomic does), or it ends up readable by its owner only.
    umask = os.umask(0)
    os.umask(umask)
    os.fchmod(fd, 0o666 & ~umask)
    os.close(fd)
    try:
        fig.savefig(tmp, format="png", dpi=DPI, bbox_inches="tight")
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    finally:
        plt.close(fig)


def _closed_kappa(rep: Mapping[str, Any]) -> np.ndarray:
    return np.asarray(rep["kappa_D0_sorted"])


def plot_closed_profiles(
    report: Mapping[str, Any], path: str | os.PathLike[str],
    ideal: Mapping[str, Any] | None = None, label: str = "knot", knot: str = "closed trefoil",
) -> None:
    """rho(s), z(s), kappa D0 (s) of a closed knot (named ``knot`` in the title), the ideal
    knot overlaid if given. A knot without a trefoil's 3-fold axis (``report["rho"]`` None,
    the reason in ``report["threefold"]``) gets the curvature panel only, its s from vertex
    0; an ideal knot placed on it by :func:`tightknot.knots.ideal_overlay.aligned` is
    labelled so."""
    threefold = report.get("rho") is not None
    series = [("rho", r"$\rho = \sqrt{X^2+Y^2}/D_0$"), ("z", r"$z = Z/D_0$")] if threefold else []
    series.append(("kappa", r"$\kappa D_0$"))
    fig, axes = plt.subplots(len(series), 1, figsize=(7, 8 if threefold else 3.6), sharex=True,
                             squeeze=False)
    axes = axes[:, 0]
    ideal_style = dict(IDEAL_STYLE)
    if ideal is not None and ideal.get("aligned"):
        ideal_style["label"] = "ideal (placed by best-matching curvature)"
    for ax, (key, name) in zip(axes, series, strict=True):
        for rep, style in ((report, {"color": COLORS[0], "label": label}), (ideal, ideal_style)):
            if rep is None:
                continue
            y = _closed_kappa(rep) if key == "kappa" else np.asarray(rep[key])
            ax.plot(rep["s"], y, **style)
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
        for s_in in report.get("inner_segments_s") or []:
            ax.axvline(s_in, color="0.8", linewidth=0.8, zorder=0)
    axes[-1].axhline(2.0, color="0.5", linewidth=0.8, linestyle=":")
    axes[-1].text(axes[-1].get_xlim()[0], 2.0, " active limit 2", va="bottom", color="0.4")
    axes[0].legend(loc="upper right")
    axes[0].set_title(f"{knot} (grey lines: inner segments)" if threefold else
                      f"{knot} (no 3-fold axis: no rho, z; s from vertex 0)")
    axes[-1].set_xlabel(r"$s = S/L \cdot L_0/D_0$")
    save_png_atomic(fig, path)


def plot_contact_map(
    report: Mapping[str, Any], path: str | os.PathLike[str],
    ideal: Mapping[str, Any] | None = None, label: str = "knot", knot: str | None = None,
) -> None:
    """Contact map (s, sigma) of a closed knot (named ``knot`` in the title); the ideal
    knot's double-contact set overlaid if given.

    For the ideal knot pass a report made with a tight ``contact_tol`` (e.g. 0.002): its
    contact set is then the double-contact lines.
    """
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.scatter(report["contact_s"], report["contact_sigma"], s=1, color=COLORS[0],
               label=label, rasterized=True)
    if ideal is not None:
        ax.scatter(ideal["contact_s"], ideal["contact_sigma"], s=0.3, color="black",
                   label="ideal (double contact)", rasterized=True)
    ax.plot([min(report["s"]), max(report["s"])], [min(report["s"]), max(report["s"])],
            color="0.7", linewidth=0.8)
    ax.set_xlabel(r"$s$")
    ax.set_ylabel(r"$\sigma$")
    ax.set_aspect("equal")
    ax.set_title("contact map" if knot is None else f"contact map: {knot}")
    ax.legend(loc="upper left", markerscale=8)
    save_png_atomic(fig, path)


def plot_open_knots(
    reports: Mapping[str, Mapping[str, Any]],
    path: str | os.PathLike[str],
    contact_width: Mapping[str, Sequence[float]] | None = None,
    area_ratio: Mapping[str, Sequence[float]] | None = None,
    pressure: Mapping[str, Sequence[float]] | None = None,
    judged_area_ratio: float | None = None,
) -> None:
    """Open knots at several tightness levels: kappa D0 (s), contact maps, L_c(s), A(s)/A0,
    p_max(s)/E.

    ``reports``: label -> analyze_centerline dict of an open knot (e.g. "Lambda_OC = 15.0").
    ``contact_width``/``area_ratio``/``pressure``: label -> per-vertex arrays (from the
    contact layer: L_c, A/A0, the largest contact pressure over E), plotted against that
    report's s. ``judged_area_ratio``: the smallest A/A0 at which the FEM judged the
    sections, drawn on the A/A0 panel (below it a section is extrapolated).
    """
    extra = [(d, n) for d, n in ((contact_width, r"$L_c$ (contact width)"),
                                  (area_ratio, r"$A/A_0$"),
                                  (pressure, r"$p_{max}/E$")) if d]
    ncol = max(len(reports), 1)
    fig = plt.figure(figsize=(5 * max(ncol, 2), 4 + 2.5 * (1 + len(extra))))
    grid = fig.add_gridspec(2 + len(extra), ncol, height_ratios=[1, 1.6] + [1] * len(extra))
    ax_k = fig.add_subplot(grid[0, :])
    extra_axes = [fig.add_subplot(grid[2 + row, :], sharex=ax_k) for row in range(len(extra))]
    for k, (lab, rep) in enumerate(reports.items()):
        c = COLORS[k % len(COLORS)]
        lam = rep.get("Lambda_OC")
        name = lab if lam is None else f"{lab} ($\\Lambda_{{OC}}$ = {lam:.1f})"
        ax_k.plot(rep["s"], rep["kappa_D0"], color=c, label=name)
        ax_m = fig.add_subplot(grid[1, k])
        ax_m.scatter(rep["contact_s"], rep["contact_sigma"], s=1, color=c, rasterized=True)
        ax_m.set_xlabel(r"$s$")
        ax_m.set_ylabel(r"$\sigma$")
        ax_m.set_aspect("equal")
        ax_m.set_title(f"contact map: {lab}")
        for ax, (data, _) in zip(extra_axes, extra, strict=True):
            if lab in data:
                ax.plot(rep["s"], data[lab], color=c, label=lab)
    for ax, (data, ylab) in zip(extra_axes, extra, strict=True):
        if data is area_ratio and judged_area_ratio is not None:
            ax.axhline(judged_area_ratio, color="0.4", linestyle="--", linewidth=0.8,
                       label=f"FEM-judged down to {judged_area_ratio:.3g}")
            ax.legend(loc="lower right")
        ax.set_ylabel(ylab)
        ax.set_xlabel(r"$s = (S - S_{mid})/D_0$")
        ax.grid(alpha=0.3)
    ax_k.set_xlabel(r"$s = (S - S_{mid})/D_0$")
    ax_k.set_ylabel(r"$\kappa D_0$")
    ax_k.grid(alpha=0.3)
    ax_k.legend()
    fig.tight_layout()
    save_png_atomic(fig, path)
