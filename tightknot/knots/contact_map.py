"""Contact map, double contact and polygonal thickness of a centerline.

Contact map (Johanns et al. 2021, physics.md sec. 2): the set of arc-length pairs (s, sigma)
whose rod surfaces touch. For a rod model a pair of centerline points is in contact when
their distance is at most the sum of their (deformed) radii; here within a relative
tolerance ``tol`` so that a polygon sampled near contact is still seen touching. Pairs closer
along the rod than the non-local window (:func:`tightknot.knots.curves.exclusion_arc_length`,
pi D / 2) are neighbours on one strand, not contacts, and are excluded.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from tightknot.knots._arclength import (
    arc_separation,
    as_points,
    edge_lengths,
    total_length,
    vertex_arclength,
)
from tightknot.knots.curves import exclusion_arc_length


def nonlocal_vertex_pairs(points: ArrayLike, closed: bool, radii: ArrayLike | float,
                          tol: float, exclusion: float | None = None, extra: float = 0.0
                          ) -> tuple[NDArray[np.float64], ...]:
    """Vertex pairs (i < j) within 2 max(radii) (1 + ``tol``) + ``extra`` [m] of each other
    that are farther apart along the curve than the non-local window ``exclusion`` [m]
    (default pi D_max / 2 with D_max = 2 max(radii)): the points (N, 3), the radii
    broadcast to (N,), i, j and the pairs' distances [m]. ``radii`` [m]: one or one per
    vertex, positive and finite."""
    p = as_points(points)
    n = p.shape[0]
    a = np.broadcast_to(np.asarray(radii, dtype=np.float64), (n,))
    if np.any(a <= 0) or not np.all(np.isfinite(a)):
        raise ValueError("radii must be positive and finite")
    if exclusion is None:
        exclusion = exclusion_arc_length(2.0 * float(a.max()))
    s = vertex_arclength(p, closed)
    length = total_length(p, closed)
    reach = 2.0 * float(a.max()) * (1.0 + tol) + extra
    pairs = cKDTree(p).query_pairs(reach, output_type="ndarray")
    if pairs.size == 0:
        e = np.zeros(0, dtype=np.int64)
        return p, a, e, e, np.zeros(0)
    i, j = pairs[:, 0], pairs[:, 1]
    keep = arc_separation(s[i], s[j], length, closed) > exclusion
    i, j = i[keep], j[keep]
    return p, a, i, j, np.linalg.norm(p[i] - p[j], axis=1)


def contact_pairs(
    points: ArrayLike,
    closed: bool,
    radii: ArrayLike | float,
    tol: float = 0.01,
    exclusion: float | None = None,
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Vertex index pairs (i, j) in contact: |r_i - r_j| <= (a_i + a_j)(1 + tol), non-local.

    ``radii``: one radius [m] or one per vertex (deformed radii of a model, D0/2 for data).
    ``exclusion``: non-local window [m], default pi D_max / 2 with D_max = 2 max(radii).
    Both orders (i, j) and (j, i) are returned, so the map is symmetric by construction;
    sorted by i then j.
    """
    p, a, i, j, d = nonlocal_vertex_pairs(points, closed, radii, tol, exclusion)
    if i.size == 0:
        e = np.zeros(0, dtype=np.int64)
        return e, e
    keep = d <= (a[i] + a[j]) * (1.0 + tol)
    i, j = i[keep], j[keep]
    ii = np.concatenate([i, j]).astype(np.int64)
    jj = np.concatenate([j, i]).astype(np.int64)
    order = np.lexsort((jj, ii))
    return ii[order], jj[order]


def partner_counts(
    points: ArrayLike, closed: bool, diameter: float, tol: float = 0.005
) -> NDArray[np.int64]:
    """Per vertex i, the number of distinct non-local partners at distance <= D (1 + tol).

    A partner is a local minimum over j of the distance |r_i - r_j| (d_j < d_{j-1} and
    d_j <= d_{j+1}): a tube touching vertex i at one place gives a whole run of vertices
    within the tolerance but one minimum, while the two strands of a double contact give two
    minima even where their runs merge (on the ideal trefoil the two partners of a vertex are
    sometimes only a small bump in distance apart, so counting runs would undercount).
    """
    p = as_points(points)
    n = p.shape[0]
    i, j = contact_pairs(p, closed, 0.5 * diameter, tol=tol)
    counts = np.zeros(n, dtype=np.int64)
    if i.size == 0:
        return counts
    d = np.linalg.norm(p[i] - p[j], axis=1)
    if closed:
        jm, jp = (j - 1) % n, (j + 1) % n
    else:
        jm, jp = np.maximum(j - 1, 0), np.minimum(j + 1, n - 1)
    dm = np.linalg.norm(p[i] - p[jm], axis=1)
    dp = np.linalg.norm(p[i] - p[jp], axis=1)
    # An open end (j = 0 or n - 1) compares with itself on one side: a minimum there counts.
    is_min = ((d < dm) | (jm == j)) & ((d <= dp) | (jp == j))
    np.add.at(counts, i[is_min], 1)
    return counts


def double_contact_fraction(
    points: ArrayLike, closed: bool, diameter: float, tol: float = 0.005
) -> float:
    """Fraction of vertices with >= 2 non-local partners at distance D within ``tol`` (relative).

    Ideal knots are in double contact almost everywhere (Carlen, Laurie, Maddocks, Smutny 2005):
    the ideal trefoil gives 1.0 at tol = 0.005 (refdata README).
    """
    counts = partner_counts(points, closed, diameter, tol)
    return float(np.mean(counts >= 2))


def minrad(points: ArrayLike, closed: bool) -> NDArray[np.float64]:
    """Rawdon's polygonal minimum radius per vertex [m]: min(|e_{i-1}|, |e_i|) / (2 tan(phi/2)).

    phi is the turning angle at the vertex (Rawdon 1998, "Approximating smooth thickness").
    Open curves: end vertices get +inf.
    """
    p = as_points(points, min_points=3)
    e = np.roll(p, -1, axis=0) - p if closed else np.diff(p, axis=0)
    l_e = np.linalg.norm(e, axis=1)
    if closed:
        e_prev, e_next, l_prev, l_next = np.roll(e, 1, 0), e, np.roll(l_e, 1), l_e
    else:
        e_prev, e_next, l_prev, l_next = e[:-1], e[1:], l_e[:-1], l_e[1:]
    cosphi = np.einsum("ij,ij->i", e_prev, e_next) / (l_prev * l_next)
    phi = np.arccos(np.clip(cosphi, -1.0, 1.0))
    with np.errstate(divide="ignore"):
        r = np.minimum(l_prev, l_next) / (2.0 * np.tan(0.5 * phi))
    if closed:
        return r
    out = np.full(p.shape[0], np.inf)
    out[1:-1] = r
    return out


def polygonal_thickness(points: ArrayLike, closed: bool = True) -> float:
    """Rawdon's polygonal thickness r = min(MinRad, dcsd / 2) [m] (refdata README convention).

    dcsd, the doubly critical self-distance, is approximated by the minimum distance between
    vertex pairs (refined on the adjacent edges) farther apart along the curve than pi r,
    the arc a tube of radius r needs to turn back on itself (see exclusion_arc_length with
    D = 2 r). Since r enters that window, it is found by a short fixed-point iteration.
    """
    from tightknot.knots.curves import min_nonlocal_distance

    p = as_points(points, min_points=3)
    r_bend = float(minrad(p, closed).min())
    r = r_bend
    for _ in range(20):
        d, _, _ = min_nonlocal_distance(p, closed, exclusion_arc_length(2.0 * r))
        r_new = min(r_bend, 0.5 * d)
        if abs(r_new - r) <= 1e-12 * r:
            break
        r = r_new
    return r


def mean_edge(points: NDArray[np.float64], closed: bool) -> float:
    """Mean edge length [m]."""
    return float(edge_lengths(points, closed).mean())
