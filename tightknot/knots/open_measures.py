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

from tightknot.knots._arclength import as_points
from tightknot.knots.contact_map import nonlocal_vertex_pairs


def contact_gaps(points: ArrayLike, closed: bool, radii: ArrayLike | float,
                 tol: float = 0.01, exclusion: float | None = None) -> NDArray[np.float64]:
    """Per vertex i: min over non-local vertices j of |r_i - r_j| - (a_i + a_j)(1 + tol)
    [m], the contact test of :func:`tightknot.knots.contact_map.contact_pairs` as a number
    (<= 0 in contact); +inf where no non-local vertex is within a contact distance plus
    an edge. ``radii``: one radius [m] or one per vertex; ``exclusion``: the non-local
    window [m] (default pi D_max / 2, D_max = 2 max(radii))."""
    p = as_points(points)
    edge = np.linalg.norm(np.diff(p, axis=0), axis=1)
    # An edge farther than the contact test: the neighbours of a contact vertex get their
    # (positive) gap too.
    p, a, i, j, d = nonlocal_vertex_pairs(p, closed, radii, tol, exclusion,
                                          extra=float(edge.max()) if edge.size else 0.0)
    gaps = np.full(p.shape[0], np.inf)
    g = d - (a[i] + a[j]) * (1.0 + tol)
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
