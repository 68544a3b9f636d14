"""The ideal knot's measures placed on a knot's own s axis, for overlays.

A trefoil's s has a natural origin (the middle of an outer segment, found by its 3-fold
symmetry: :func:`tightknot.knots.closed_measures.closed_knot_profile`), so the ideal
trefoil's profiles overlay a tied one as they are. Another knot's s runs from its vertex 0
(:func:`tightknot.knots.measure.analyze_centerline`), an origin with no meaning, so the
ideal knot's profile is first shifted along the knot, and read in either direction, to the
placement where its curvature kappa D (s) best matches the knot's: the largest circular
cross-correlation of the two profiles, each sampled at :data:`GRID` points of its own
arc-length fraction S/L.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tightknot.knots.ideal import has_ideal, load_ideal
from tightknot.knots.measure import analyze_centerline

#: Samples of the arc-length fraction on which the profiles are correlated: 1/1024 of the
#: knot, about 0.02 D on a knot of L/D 20, below the 0.05 D vertex spacing of the polygons.
GRID = 1024
#: Contact tolerance of the ideal knot's contact map: 0.2 % of D keeps only the double-
#: contact lines of the tight knot (tightknot.viz.figures.plot_contact_map).
IDEAL_CONTACT_TOL = 0.002


def ideal_report(knot_type: str, diameter: float) -> dict[str, Any] | None:
    """:func:`~tightknot.knots.measure.analyze_centerline` of the shipped ideal knot of
    ``knot_type`` at tube diameter ``diameter`` [m] (None when none is shipped)."""
    if not has_ideal(knot_type):
        return None
    return analyze_centerline(load_ideal(knot_type, diameter), diameter, True,
                              contact_tol=IDEAL_CONTACT_TOL)


def _profile(report: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, float]:
    s = np.asarray(report["s"], dtype=np.float64)
    period = report["rest_length_L0"] / report["diameter_D0"]
    kappa = np.asarray(report["kappa_D0_sorted"], dtype=np.float64)
    frac = np.linspace(0.0, 1.0, GRID, endpoint=False)
    base = s[0]
    on_grid = np.interp(frac * period + base, s, kappa, period=period)
    return on_grid - on_grid.mean(), s, period


def aligned(report: dict[str, Any], ideal: dict[str, Any]) -> dict[str, Any]:
    """``ideal`` (a closed knot's measures) with its s, kappa profile and contact map moved
    onto ``report``'s s axis (module docstring); unchanged when both are placed by their
    3-fold symmetry (trefoils). The result's ``"aligned"`` says which placement was taken:
    {"shift_fraction": f, "reversed": bool, "correlation": c} or None."""
    if report.get("threefold", {}).get("applied") and ideal.get("threefold", {}).get("applied"):
        return {**ideal, "aligned": None}
    k_run, s_run, p_run = _profile(report)
    k_id, s_id, p_id = _profile(ideal)
    best = (-np.inf, 0, False)
    for rev in (False, True):
        k = k_id[(-np.arange(GRID)) % GRID] if rev else k_id
        # c[m] = sum_j run[j] ideal[j + m]: the ideal shifted by m samples onto the run.
        corr = np.fft.irfft(np.conj(np.fft.rfft(k_run)) * np.fft.rfft(k), n=GRID)
        m = int(np.argmax(corr))
        if corr[m] > best[0]:
            best = (float(corr[m]), m, rev)
    c, m, rev = best
    norm = float(np.linalg.norm(k_run) * np.linalg.norm(k_id)) or 1.0

    def move(values: Any) -> np.ndarray:
        # Fraction f of the ideal's own s (from its start s_id[0]) to the run's s axis.
        f = (np.asarray(values, dtype=np.float64) - s_id[0]) / p_id
        f = (-f if rev else f) - m / GRID
        return s_run[0] + (f % 1.0) * p_id

    s_new = move(s_id)
    order = np.argsort(s_new, kind="stable")
    out = dict(ideal)
    out.update(s=s_new[order].tolist(),
               kappa_D0_sorted=np.asarray(ideal["kappa_D0_sorted"])[order].tolist(),
               contact_s=move(ideal["contact_s"]).tolist(),
               contact_sigma=move(ideal["contact_sigma"]).tolist(),
               aligned={"shift_fraction": m / GRID, "reversed": rev,
                        "correlation": c / norm})
    return out
