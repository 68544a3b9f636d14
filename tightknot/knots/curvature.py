"""Discrete curvature of a centerline and its spikes.

Bergou, Wardetzky, Robinson, Audoly, Grinspun, "Discrete elastic rods", ACM TOG 27 (2008),
eq. (1) and sec. 4.2: the curvature binormal (kappa b)_i = 2 e_{i-1} x e_i /
(|e_{i-1}||e_i| + e_{i-1} . e_i), of magnitude 2 tan(phi_i / 2) with phi_i the turning angle,
divided by the Voronoi length (|e_{i-1}| + |e_i|)/2 to give a curvature per unit length.
This is the definition of Johanns et al. 2021 (physics.md, section 2).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tightknot.knots._arclength import as_points, edges


def bergou_curvature(points: ArrayLike, closed: bool) -> NDArray[np.float64]:
    """Vertex curvature K_i [1/m], shape (N,), Bergou et al. 2008 eq. (1) over Voronoi length.

    K_i = 2 |e_{i-1} x e_i| / (|e_{i-1}||e_i| + e_{i-1} . e_i) / ((|e_{i-1}| + |e_i|) / 2).
    Open curves: the two end vertices have one edge only and no turning angle; they get
    K = 0 (a free, unloaded rod end carries no bending moment), so arrays stay aligned with
    the vertices and NaN-free. A full reversal (e_{i-1} = -e_i) is infinite curvature: raise.
    """
    p = as_points(points, min_points=3)
    e = edges(p, closed)
    if closed:
        e_prev, e_next = np.roll(e, 1, axis=0), e
    else:
        e_prev, e_next = e[:-1], e[1:]
    l_prev = np.linalg.norm(e_prev, axis=1)
    l_next = np.linalg.norm(e_next, axis=1)
    cross = np.linalg.norm(np.cross(e_prev, e_next), axis=1)
    den = l_prev * l_next + np.einsum("ij,ij->i", e_prev, e_next)
    if np.any(den <= 1e-14 * l_prev * l_next):
        raise ValueError("polygon folds back on itself (turning angle of 180 degrees)")
    k = 2.0 * cross / den / (0.5 * (l_prev + l_next))
    if closed:
        return k
    out = np.zeros(p.shape[0])
    out[1:-1] = k
    return out


def find_spikes(
    kappa: NDArray[np.float64], s: NDArray[np.float64], threshold: float, closed: bool
) -> list[dict[str, float]]:
    """Contiguous runs where ``kappa`` > ``threshold`` (same units), with their peak.

    Returns one dict per run: ``s_start``, ``s_end``, ``s_peak`` (same units as ``s``) and
    ``kappa_peak``. On a closed curve a run crossing the end of the arrays is merged with the
    one at the start.
    """
    above = np.asarray(kappa) > threshold
    n = above.size
    if not above.any():
        return []
    if above.all():
        i = int(np.argmax(kappa))
        return [{"s_start": float(s[0]), "s_end": float(s[-1]), "s_peak": float(s[i]),
                 "kappa_peak": float(kappa[i])}]
    # Start the scan at a vertex below threshold so no run wraps (closed curves).
    shift = int(np.argmin(above)) if closed else 0
    idx = np.roll(np.arange(n), -shift)
    runs = []
    cur: list[int] = []
    for i in idx:
        if above[i]:
            cur.append(int(i))
        elif cur:
            runs.append(cur)
            cur = []
    if cur:
        runs.append(cur)
    out = []
    for run in runs:
        peak = max(run, key=lambda j: kappa[j])
        out.append({"s_start": float(s[run[0]]), "s_end": float(s[run[-1]]),
                    "s_peak": float(s[peak]), "kappa_peak": float(kappa[peak])})
    out.sort(key=lambda d: d["s_peak"])
    return out
