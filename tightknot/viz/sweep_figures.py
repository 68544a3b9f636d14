"""The figures of a tightness sweep, from the flat table of its store (never physics).

Rows are those of :func:`tightknot.sweep.table.table_rows` (plain dicts), one line per
case: pulling force against Lambda_OC, force against end-to-end distance (the
force-extension curve), and stretch and min A/A0 against force. A missed level is drawn
as a cross at its last good state, so a gap in a curve is visible as such; a reached level
that left the range its contact model was calibrated or judged in (the row's
``outside_calibrated_range``) is ringed, so an extrapolated point does not pass for a
judged one.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

#: File names of the figures, by what they show.
FORCE_LAMBDA_PNG = "force_lambda_oc.png"
FORCE_EXTENSION_PNG = "force_extension.png"
STRETCH_AREA_PNG = "stretch_area_vs_force.png"
FIGURES = (FORCE_LAMBDA_PNG, FORCE_EXTENSION_PNG, STRETCH_AREA_PNG)

#: Parameters never worth a legend entry (the same in every case of a sweep by design).
_NOT_IN_LEGEND = ("case_id", "status", "knot")


def _cases(rows: Sequence[Mapping[str, Any]]) -> dict[str, list[Mapping[str, Any]]]:
    """Rows of open-knot levels grouped by case, in order."""
    out: dict[str, list[Mapping[str, Any]]] = {}
    for r in rows:
        if r.get("level_kind") is not None:
            out.setdefault(r["case_id"], []).append(r)
    return out


def marked_levels(levels: Sequence[Mapping[str, Any]], xkey: str, ykey: str
                  ) -> tuple[list[Mapping[str, Any]], list[Mapping[str, Any]],
                             list[Mapping[str, Any]]]:
    """One case's levels that have both values: (reached, missed, reached but outside the
    calibrated range)."""
    has = [r for r in levels if r.get(xkey) is not None and r.get(ykey) is not None]
    ok = [r for r in has if r["reached"]]
    return (ok, [r for r in has if not r["reached"]],
            [r for r in ok if r.get("outside_calibrated_range")])


def case_legends(rows: Sequence[Mapping[str, Any]], params: Sequence[str]) -> dict[str, str]:
    """Legend of each case: the parameters that differ between the cases (all cases the
    same: the rest length and the mesh, which define an open knot's scene)."""
    cases = _cases(rows)
    first = {cid: lv[0] for cid, lv in cases.items()}
    varying = [p for p in params if p not in _NOT_IN_LEGEND
               and len({repr(r.get(p)) for r in first.values()}) > 1]
    shown = varying or ["length", "nodes"]
    return {cid: ", ".join(f"{p}={r.get(p):g}" if isinstance(r.get(p), float)
                           else f"{p}={r.get(p)}" for p in shown)
            for cid, r in first.items()}


def plot_tightness_sweep(rows: Sequence[Mapping[str, Any]], params: Sequence[str],
                         folder: Path) -> list[Path]:
    """Draw :data:`FIGURES` into ``folder`` (created) from the table ``rows`` whose scene
    parameters are ``params``; returns the paths. ValueError when no row is an open
    knot's level (a closed sweep has no force to plot against)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = _cases(rows)
    if not cases:
        raise ValueError("the store holds no open-knot levels: the tightness plots need a "
                         "sweep of an open knot (--lambda or --force)")
    legends = case_legends(rows, params)
    folder.mkdir(parents=True, exist_ok=True)

    def draw(ax: Any, xkey: str, ykey: str, xscale: float = 1.0) -> None:
        for cid, levels in cases.items():
            ok, missed, outside = marked_levels(levels, xkey, ykey)
            line, = ax.plot([r[xkey] * xscale for r in ok], [r[ykey] for r in ok], "o-",
                            ms=4, label=legends[cid])
            if missed:
                ax.plot([r[xkey] * xscale for r in missed], [r[ykey] for r in missed], "x",
                        color=line.get_color(), ms=8, label=f"{legends[cid]}: not reached")
            if outside:
                ax.plot([r[xkey] * xscale for r in outside], [r[ykey] for r in outside], "o",
                        mfc="none", color=line.get_color(), ms=10,
                        label=f"{legends[cid]}: outside the calibrated range")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)

    paths = []
    fig, ax = plt.subplots(figsize=(5.5, 4))
    draw(ax, "lambda_oc", "pull_force_N")
    ax.set_xlabel("knot length Lambda_OC = l_OC / D0")
    ax.set_ylabel("pulling force F [N]")
    ax.set_title("tightness: force against knot length")
    fig.tight_layout()
    paths.append(folder / FORCE_LAMBDA_PNG)
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(5.5, 4))
    draw(ax, "end_to_end_m", "pull_force_N", xscale=1e3)
    ax.set_xlabel("end-to-end distance [mm]")
    ax.set_ylabel("pulling force F [N]")
    ax.set_title("force-extension")
    fig.tight_layout()
    paths.append(folder / FORCE_EXTENSION_PNG)
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.8))
    draw(a1, "pull_force_N", "stretch")
    a1.set_xlabel("pulling force F [N]")
    a1.set_ylabel("stretch L / L0")
    draw(a2, "pull_force_N", "min_area_ratio")
    a2.set_xlabel("pulling force F [N]")
    a2.set_ylabel("min section area A / A0")
    fig.suptitle("stretch and section constriction against force")
    fig.tight_layout()
    paths.append(folder / STRETCH_AREA_PNG)
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)
    return paths
