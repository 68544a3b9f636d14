"""``analyze_centerline``: every measure of physics.md sec. 2 on one centerline, as plain JSON.

Pipeline: (optional) the study's smoothing (resample at a fixed step, Gaussian average;
:mod:`tightknot.knots.smoothing`), Bergou curvature (:mod:`tightknot.knots.curvature`),
lengths and the reduced diameter, the contact map (:mod:`tightknot.knots.contact_map`), the
closed-knot profile (:mod:`tightknot.knots.closed_measures`) or the open-knot length
(:mod:`tightknot.knots.open_measures`), and the knot type (:mod:`tightknot.knots.topology`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from tightknot.knots._arclength import as_points, total_length, vertex_arclength
from tightknot.knots.closed_measures import barycenter, closed_knot_profile
from tightknot.knots.contact_map import contact_pairs, double_contact_fraction
from tightknot.knots.curvature import bergou_curvature, find_spikes
from tightknot.knots.curves import exclusion_arc_length, min_nonlocal_distance, resample_uniform
from tightknot.knots.knot_table import determinant, knot_name
from tightknot.knots.open_measures import contact_gaps
from tightknot.knots.smoothing import study_smooth, study_window
from tightknot.knots.topology import (
    TopologyError,
    alexander_polynomial,
    close_open_curve,
)

#: The study's resampling step relative to D0: N_b = 984 points on L0 = 139.1 mm gives
#: 0.1414 mm = D0 / 60 for D0 = 8.5 mm (Johanns et al. 2021; within their 0.1 to 0.15 mm).
STUDY_STEP_OVER_D0 = 1.0 / 60.0


#: The knot type whose 3-fold axis the closed measures rho, z, the origin of s and the
#: inner/outer segments are taken about (Johanns et al. 2021 define them for the trefoil).
THREEFOLD_KNOT = "3_1"


def threefold_reason(knot_type: str) -> str:
    """Why a closed curve of ``knot_type`` (not a trefoil) gets no 3-fold measures."""
    return (f"rho, z, the origin of s and the inner/outer segments are measured about a "
            f"trefoil's 3-fold axis (Johanns et al. 2021); this curve is {knot_type}: s runs "
            "from vertex 0, rho, z and the segments are null")


def reduced_diameter(diameter: float, length: float, rest_length: float, poisson: float) -> float:
    """D = D0 [1 - nu (L - L0) / L0] [m] (Johanns et al. 2021; linearised lateral contraction)."""
    return diameter * (1.0 - poisson * (length - rest_length) / rest_length)


def _list(a: Any) -> Any:
    return np.asarray(a, dtype=np.float64).tolist()


def analyze_centerline(
    points: ArrayLike,
    diameter: float,
    closed: bool,
    smooth_n_gauss: float | None = None,
    rest_length: float | None = None,
    poisson: float = 0.5,
    radii: ArrayLike | None = None,
    contact_tol: float = 0.01,
    spike_threshold: float = 1.8,
    step: float | None = None,
    double_contact_tol: float = 0.005,
) -> dict[str, Any]:
    """Measure a centerline (N, 3) [m] of a rod of rest diameter ``diameter`` = D0 [m].

    Parameters
    ----------
    smooth_n_gauss: None measures the raw polygon; a number N_gauss applies the study's
        smoothing first (resample at ``step``, default D0/60, then window round(N_b/N_gauss)).
    rest_length: L0 [m]; default the measured length L (then stretch = 1, D = D0).
    poisson: nu of the reduced diameter D = D0 [1 - nu (L - L0)/L0].
    radii: per-vertex deformed radii [m] for the contact map (only with the raw polygon,
        whose vertices they belong to); "stretch": each section thinned by its local
        stretch, r0 lambda^-nu (lambda: an edge's length over L0 / edges, a rod of equal
        rest edges, as the package's scenes; the vertex takes its edges' mean), which is
        how a tie's summary measures its own centerline; default D0/2 (measured data).
    contact_tol: relative tolerance of the contact test (distance <= (a_i + a_j)(1 + tol)).
    spike_threshold: kappa*D0 above which a run of vertices is a curvature spike.
    double_contact_tol: relative tolerance of the double-contact check (ideal knots).

    Returns a JSON-serialisable dict (lists and floats; no NaN except ``Lambda_OC``/``S1``/
    ``S2`` of an open curve without contact, which are None). Keys are listed in the README
    of the package (tightknot/knots/__init__.py docstring).
    """
    p = as_points(points, min_points=3)
    d0 = float(diameter)
    if d0 <= 0:
        raise ValueError("diameter must be positive")
    raw_length = total_length(p, closed)
    out: dict[str, Any] = {"closed": bool(closed), "diameter_D0": d0, "smoothed": False}
    if smooth_n_gauss is not None:
        h = d0 * STUDY_STEP_OVER_D0 if step is None else float(step)
        p = study_smooth(p, closed, h, n_gauss=smooth_n_gauss)
        out.update(smoothed=True, smooth_n_gauss=float(smooth_n_gauss), resample_step=h,
                   smooth_window_points=study_window(p.shape[0], smooth_n_gauss),
                   length_before_smoothing=raw_length)
        if radii is not None and not isinstance(radii, str) and np.ndim(radii) > 0:
            raise ValueError("per-vertex radii cannot be combined with smoothing (resampled)")
    n = p.shape[0]
    length = total_length(p, closed)
    l0 = length if rest_length is None else float(rest_length)
    d_red = reduced_diameter(d0, length, l0, poisson)
    S = vertex_arclength(p, closed)
    kappa = bergou_curvature(p, closed) * d0  # kappa = K D0 (Johanns et al. 2021)
    out.update(
        n_points=n, length_L=length, rest_length_L0=l0, stretch_L_over_L0=length / l0,
        poisson=poisson, reduced_diameter_D=d_red, L_over_D=length / d_red,
        L_over_D0=length / d0, S=_list(S), kappa_D0=_list(kappa),
        kappa_D0_max=float(kappa.max()), kappa_D0_min=float(kappa[1:-1].min() if not closed
                                                             else kappa.min()),
        kappa_D0_mean=float(np.mean(kappa if closed else kappa[1:-1])),
    )
    # Knot type: an open curve is closed far away along its end-to-end axis first.
    try:
        poly = alexander_polynomial(p if closed else close_open_curve(p))
        out.update(alexander_polynomial=poly, knot_determinant=determinant(poly),
                   knot_type=knot_name(poly))
    except TopologyError as exc:
        out.update(alexander_polynomial=None, knot_determinant=None,
                   knot_type=f"undetermined: {exc}")
    dmin, sa, sb = min_nonlocal_distance(p, closed, exclusion_arc_length(d0))
    out.update(min_nonlocal_distance_over_D0=dmin / d0 if np.isfinite(dmin) else None,
               min_nonlocal_pair_S=[sa, sb] if np.isfinite(dmin) else None)
    if isinstance(radii, str):
        if radii != "stretch":
            raise ValueError(f"radii must be per-vertex values or 'stretch', got {radii!r}")
        if smooth_n_gauss is not None:
            raise ValueError("radii='stretch' cannot be combined with smoothing (resampled)")
        a = stretch_radii(p, d0, l0, poisson, closed)
    else:
        a = 0.5 * d0 if radii is None else np.asarray(radii, dtype=np.float64)
    ci, cj = contact_pairs(p, closed, a, tol=contact_tol)
    out["contact_tol"] = contact_tol
    out["spike_threshold_kappa_D0"] = spike_threshold
    if closed and out["knot_type"] != THREEFOLD_KNOT:
        # No 3-fold axis to measure about: arc length from vertex 0, rho/z/segments null.
        s_v = S * (l0 / (length * d0))
        out.update(
            s=_list(s_v), vertex_order=list(range(n)), S_sorted=_list(S),
            kappa_D0_sorted=_list(kappa), rho=None, z=None, X_over_D0=None, Y_over_D0=None,
            origin_S=0.0, axis=None, barycenter=_list(barycenter(p)),
            inplane_spread_ratio=None, outer_segments_s=None, inner_segments_s=None,
            contact_s=_list(s_v[ci]), contact_sigma=_list(s_v[cj]),
            double_contact_fraction=double_contact_fraction(p, True, d0, double_contact_tol),
            threefold={"applied": False, "reason": threefold_reason(out["knot_type"])},
        )
        spikes = find_spikes(kappa, s_v, spike_threshold, closed=True)
    elif closed:
        prof = closed_knot_profile(p, d0, l0)
        order = prof.pop("order")
        rank = np.empty(n, dtype=np.int64)
        rank[order] = np.arange(n)
        s_vertex = np.empty(n)
        s_vertex[order] = prof["s"]
        out.update(
            s=_list(prof["s"]), vertex_order=order.tolist(), S_sorted=_list(S[order]),
            kappa_D0_sorted=_list(kappa[order]), rho=_list(prof["rho"]), z=_list(prof["z"]),
            X_over_D0=_list(prof["X_over_D0"]), Y_over_D0=_list(prof["Y_over_D0"]),
            origin_S=prof["origin_S"], axis=_list(prof["axis"]),
            barycenter=_list(prof["barycenter"]),
            inplane_spread_ratio=prof["inplane_spread_ratio"],
            outer_segments_s=prof["outer_segments_s"],
            inner_segments_s=prof["inner_segments_s"],
            contact_s=_list(s_vertex[ci]), contact_sigma=_list(s_vertex[cj]),
            double_contact_fraction=double_contact_fraction(p, True, d0, double_contact_tol),
            threefold={"applied": True, "reason": "the curve is a trefoil (3_1)"},
        )
        spikes = find_spikes(kappa[order], prof["s"], spike_threshold, closed=True)
    else:
        gaps = contact_gaps(p, False, a, tol=contact_tol)
        om = open_knot_measures_dict(gaps, S, d0)
        s_open = om.pop("s")
        out.update(om)
        out.update(s=_list(s_open), contact_s=_list(s_open[ci]), contact_sigma=_list(s_open[cj]))
        spikes = find_spikes(kappa, s_open, spike_threshold, closed=False)
    out["curvature_spikes"] = spikes
    out["n_curvature_spikes"] = len(spikes)
    return out


def stretch_radii(points: np.ndarray, diameter: float, rest_length: float, poisson: float,
                  closed: bool) -> np.ndarray:
    """Per-vertex radii [m] of a rod of rest length ``rest_length`` [m] whose sections thin
    with its mean stretch lambda = L/L0: r0 lambda^-nu at every vertex (the default contact
    level's sections, :func:`tightknot.knots.scenes.vertex_radii`)."""
    e = np.linalg.norm((np.roll(points, -1, axis=0) - points) if closed
                       else np.diff(points, axis=0), axis=1)
    lam = float(e.sum()) / rest_length
    return np.full(points.shape[0], 0.5 * diameter * lam ** (-poisson))


def open_knot_measures_dict(gaps: np.ndarray, S: np.ndarray, d0: float) -> dict[str, Any]:
    """Open-knot entries of :func:`analyze_centerline` from the vertex contact gaps
    (:func:`tightknot.knots.open_measures.contact_gaps`; NaN written as None for JSON)."""
    from tightknot.knots.open_measures import open_knot_measures

    om = open_knot_measures(gaps, S, d0)

    def clean(v: float) -> float | None:
        return None if np.isnan(v) else float(v)

    return {"Lambda_OC": clean(om["Lambda_OC"]), "contact_S1": clean(om["S1"]),
            "contact_S2": clean(om["S2"]), "S_mid": om["S_mid"], "s": om["s"]}


def resampled(points: ArrayLike, n: int, closed: bool) -> np.ndarray:
    """Uniform resampling to n vertices (re-exported for callers comparing resolutions)."""
    return resample_uniform(points, n, closed)
