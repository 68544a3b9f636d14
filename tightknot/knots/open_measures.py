"""Measures of an open knot: knot length Lambda_OC and the arc length centred on the knot.

Johanns et al. 2021 (physics.md sec. 2): Lambda_OC = (s_2 - s_1) / D0, with s_1, s_2 the arc
lengths of the first (entrance) and last (exit) contact points along the rod; open-knot arc
length s = S / D0 with s = 0 at the middle of the knot, (S_1 + S_2) / 2.

The contact points lie between vertices: each vertex's gap (its distance to the nearest
non-local vertex less the contact distance, :func:`contact_gaps`) changes sign between the
last vertex out of contact and the first in contact, and the entrance is where the gap,
linear along that edge, vanishes (likewise the exit). So Lambda_OC moves continuously with
the shape instead of by whole edges as the contact set gains or loses a vertex. This is the
one Lambda_OC of the package: the tie's summaries, the load paths' searches and ``analyze``
all compute it here.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from tightknot.knots._arclength import arc_separation, as_points, total_length, vertex_arclength
from tightknot.knots.curves import exclusion_arc_length


def contact_gaps(points: ArrayLike, closed: bool, radii: ArrayLike | float,
                 tol: float = 0.01, exclusion: float | None = None) -> NDArray[np.float64]:
    """Per vertex i: min over non-local vertices j of |r_i - r_j| - (a_i + a_j)(1 + tol)
    [m], the contact test of :func:`tightknot.knots.contact_map.contact_pairs` as a number
    (<= 0 in contact); +inf where no non-local vertex is within a contact distance plus
    an edge. ``radii``: one radius [m] or one per vertex; ``exclusion``: the non-local
    window [m] (default pi D_max / 2, D_max = 2 max(radii))."""
    p = as_points(points)
    n = p.shape[0]
    a = np.broadcast_to(np.asarray(radii, dtype=np.float64), (n,))
    if np.any(a <= 0) or not np.all(np.isfinite(a)):
        raise ValueError("radii must be positive and finite")
    if exclusion is None:
        exclusion = exclusion_arc_length(2.0 * float(a.max()))
    s = vertex_arclength(p, closed)
    length = total_length(p, closed)
    edge = np.linalg.norm(np.diff(p, axis=0), axis=1)
    # Far enough to give the neighbours of a contact vertex their (positive) gap too.
    reach = 2.0 * float(a.max()) * (1.0 + tol) + (float(edge.max()) if edge.size else 0.0)
    gaps = np.full(n, np.inf)
    pairs = cKDTree(p).query_pairs(reach, output_type="ndarray")
    if pairs.size == 0:
        return gaps
    i, j = pairs[:, 0], pairs[:, 1]
    keep = arc_separation(s[i], s[j], length, closed) > exclusion
    i, j = i[keep], j[keep]
    g = np.linalg.norm(p[i] - p[j], axis=1) - (a[i] + a[j]) * (1.0 + tol)
    np.minimum.at(gaps, i, g)
    np.minimum.at(gaps, j, g)
    return gaps


def knot_extent(gaps: NDArray[np.float64], S: NDArray[np.float64]) -> tuple[float, float]:
    """Arc lengths (S_1, S_2) [m] of the entrance and exit contact points from the vertex
    gaps (module docstring); NaN if no vertex is in contact."""
    inside = np.flatnonzero(gaps <= 0.0)
    if inside.size == 0:
        return float("nan"), float("nan")
    i1, i2 = int(inside[0]), int(inside[-1])
    s1, s2 = float(S[i1]), float(S[i2])
    if i1 > 0 and np.isfinite(gaps[i1 - 1]):
        # The gap, linear along edge (i1 - 1, i1), vanishes at this fraction from i1 - 1.
        u = gaps[i1 - 1] / (gaps[i1 - 1] - gaps[i1])
        s1 = float(S[i1 - 1] + u * (S[i1] - S[i1 - 1]))
    if i2 < len(S) - 1 and np.isfinite(gaps[i2 + 1]):
        u = gaps[i2] / (gaps[i2] - gaps[i2 + 1])
        s2 = float(S[i2] + u * (S[i2 + 1] - S[i2]))
    return s1, s2


def open_knot_measures(gaps: NDArray[np.float64], S: NDArray[np.float64],
                       diameter: float) -> dict[str, float | NDArray]:
    """Lambda_OC, S_1, S_2 [m] and s = (S - S_mid) / D0 from the vertex gaps.

    ``gaps``: :func:`contact_gaps`; ``S``: vertex arc lengths [m] from the first end;
    ``diameter`` = D0 [m]. With no contact the knot has no extent: Lambda_OC is NaN and s is
    centred on the rod's middle instead.
    """
    s1, s2 = knot_extent(gaps, S)
    if np.isnan(s1):
        mid = 0.5 * (S[0] + S[-1])
        lam = float("nan")
    else:
        mid = 0.5 * (s1 + s2)
        lam = (s2 - s1) / diameter
    return {"Lambda_OC": lam, "S1": s1, "S2": s2, "S_mid": float(mid),
            "s": (S - mid) / diameter}


def lambda_oc(x: np.ndarray, diameter: float, radii: np.ndarray | float | None = None,
              tol: float = 0.01) -> float:
    """Open-knot length Lambda_OC of centerline ``x`` (physics.md sec. 2), NaN without
    contact; contact where the distance is at most (1 + tol) times the sum of the radii
    (default D0/2; pass the deformed radii of a simulation, as the summaries do)."""
    r = np.full(len(x), diameter / 2) if radii is None else radii
    gaps = contact_gaps(x, False, r, tol=tol)
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))]
    return float(open_knot_measures(gaps, s, diameter)["Lambda_OC"])
