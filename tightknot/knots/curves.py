"""Parametric knot curves, arc-length resampling, and scaling a curve to a rod diameter.

All lengths in metres (or any one unit, consistently). Closed curves do not repeat their
first vertex.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from tightknot.knots._arclength import (
    as_points,
    edge_lengths,
    resample_uniform,
    total_length,
    vertex_arclength,
)


def trefoil(n: int = 400, size: float = 1.0) -> NDArray[np.float64]:
    """Closed trefoil (3_1), n vertices [m]: x = sin t + 2 sin 2t, y = cos t - 2 cos 2t,
    z = -sin 3t, t in [0, 2 pi), times ``size``. Left-handed in this orientation."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    p = np.stack([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)], 1)
    return size * p


def figure_eight(n: int = 400, size: float = 1.0) -> NDArray[np.float64]:
    """Closed figure-eight knot (4_1), n vertices [m]: x = (2 + cos 2t) cos 3t,
    y = (2 + cos 2t) sin 3t, z = sin 4t, times ``size``."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    r = 2 + np.cos(2 * t)
    return size * np.stack([r * np.cos(3 * t), r * np.sin(3 * t), np.sin(4 * t)], axis=1)


def circle(n: int = 100, radius: float = 1.0) -> NDArray[np.float64]:
    """Closed circle of ``radius`` [m] in the x-y plane, n vertices."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return radius * np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], axis=1)


def helix(n: int, radius: float, pitch_over_2pi: float, turns: float) -> NDArray[np.float64]:
    """Open helix r(t) = (a cos t, a sin t, b t), a = ``radius``, b = ``pitch_over_2pi`` [m].

    Exact curvature a / (a^2 + b^2) [1/m] (used to test the discrete curvature).
    """
    t = np.linspace(0.0, 2 * np.pi * turns, n)
    return np.stack([radius * np.cos(t), radius * np.sin(t), pitch_over_2pi * t], axis=1)


def _open_from_closed(closed_pts: NDArray[np.float64], gap: float, offset: float,
                      tail: float, n: int) -> NDArray[np.float64]:
    """Cut a closed knot at its outermost point (in the x-y projection) and add straight tails.

    The knot is cut at the vertex farthest from the z axis, leaving a gap of ``gap`` times the
    knot length. Each end goes radially out by ``offset`` and then straight along the tangent
    line of that outermost point (the pull axis, away from the other end) for ``tail``. The
    tails lie outside the disc that contains the whole projection, so they add no crossing;
    closing them through infinity recovers the original knot type (the outer face of a
    diagram is a disc on the sphere, so any closure inside it is isotopic).
    """
    m = closed_pts.shape[0]
    rad = np.linalg.norm(closed_pts[:, :2], axis=1)
    k = int(np.argmax(rad))
    pts = np.roll(closed_pts, -k, axis=0)  # outermost point first
    length = total_length(pts, closed=True)
    s = vertex_arclength(pts, closed=True)
    keep = (s > 0.5 * gap * length) & (s < length - 0.5 * gap * length)
    body = pts[keep]
    tip = pts[0]
    r_hat = np.array([tip[0], tip[1], 0.0]) / np.hypot(tip[0], tip[1])
    tangent = pts[1] - pts[-1]
    tangent[2] = 0.0
    tangent -= (tangent @ r_hat) * r_hat
    tangent /= np.linalg.norm(tangent)
    start, end = body[0], body[-1]  # start lies on the +tangent side, end on the -tangent side
    a_out = start + offset * r_hat
    b_out = end + offset * r_hat
    a_far = a_out + tail * tangent
    b_far = b_out - tail * tangent
    poly = np.vstack([a_far, a_out, body, b_out, b_far])
    pull = poly[-1] - poly[0]
    out = resample_uniform(poly, n, closed=False)
    # Round the corners where the tails join the knot: a light Gaussian average in arc length
    # (the straight tails and the end points are preserved by the odd reflection at the ends).
    from tightknot.knots.smoothing import gaussian_smooth_points

    out = gaussian_smooth_points(out, closed=False, std_points=max(1.0, n / m * 2.0),
                                 ends="reflect")
    _ = pull
    return out


def open_trefoil(n: int = 600, size: float = 1.0, tail: float = 6.0) -> NDArray[np.float64]:
    """Loose open trefoil (overhand knot) with straight tails along a pull axis [m].

    Built from :func:`trefoil` (times ``size``) cut at its outermost lobe; the tails have
    length ``tail * size`` each. The pull axis is the end-to-end direction.
    """
    base = trefoil(2000, 1.0)
    pts = _open_from_closed(base, gap=0.03, offset=0.6, tail=tail, n=n)
    return size * pts


def open_figure_eight(n: int = 800, size: float = 1.0, tail: float = 6.0) -> NDArray[np.float64]:
    """Loose open figure-eight knot with straight tails along a pull axis [m] (see
    :func:`open_trefoil`)."""
    base = figure_eight(2000, 1.0)
    pts = _open_from_closed(base, gap=0.03, offset=0.6, tail=tail, n=n)
    return size * pts


def resample_equal_chords(points: ArrayLike, n: int) -> NDArray[np.float64]:
    """Resample an open polygon to ``n`` vertices with equal chords [m].

    The vertices lie on the polygon, the first and last at its ends, and every edge has
    the same length: the discretisation of a uniform rod whose rest lengths are its start's
    edge lengths (``resample_uniform`` spaces the vertices equally in arc length instead,
    so its chords fall short where the curve bends: 4.5 % at the tails' corners of a
    150-vertex trefoil, which makes the rod non-uniform there). The chord c is found by
    bisection so that n - 1 steps of length c, each to the first point of the polygon at
    distance c from the last, end at the polygon's end (to 1e-12 of its length).
    """
    p = as_points(points)
    if n < 2:
        raise ValueError(f"n must be at least 2, got {n}")
    lengths = edge_lengths(p, closed=False)
    if np.any(lengths == 0):
        p = p[np.concatenate([[True], lengths > 0])]
        lengths = lengths[lengths > 0]
    s = np.concatenate([[0.0], np.cumsum(lengths)])

    def walk(c: float) -> tuple[NDArray[np.float64], float]:
        # Returns the points and how much polygon arc is left after n - 1 steps (< 0:
        # the walk ran off the end, by the missing steps' length).
        out = np.empty((n, 3))
        out[0] = p[0]
        cur, j, t = p[0], 0, 0.0  # current point: on segment j at parameter t
        for k in range(1, n):
            # first vertex ahead at distance >= c from cur: the crossing is on the segment
            # before it (or on segment j itself, past t)
            # (looked for within 4 c of arc first: a chord of c spans at least c of arc,
            # and on the knots' curves little more)
            end = int(np.searchsorted(s, s[j] + t * lengths[j] + 4.0 * c)) + 1
            d = np.linalg.norm(p[j + 1:end + 1] - cur, axis=1)
            ahead = np.flatnonzero(d >= c)
            if not ahead.size:
                d = np.linalg.norm(p[j + 1:] - cur, axis=1)
                ahead = np.flatnonzero(d >= c)
            if not ahead.size:
                return out, -(n - k) * c
            jj = j + int(ahead[0])  # segment jj runs from p[jj] to p[jj + 1]
            a, b = p[jj], p[jj + 1]
            u = b - a
            w = a - cur
            # |w + tau u|^2 = c^2: the larger root (leaving the sphere; qc <= 0 inside),
            # in the form without cancellation (Press et al., Numerical Recipes sec. 5.6)
            qa, qb, qc = u @ u, 2.0 * (w @ u), w @ w - c * c
            root = np.sqrt(max(qb * qb - 4.0 * qa * qc, 0.0))
            tau = (2.0 * qc / (-qb - root) if qb > 0.0 and root + qb > 0.0
                   else (-qb + root) / (2.0 * qa))
            tau = min(max(tau, t if jj == j else 0.0), 1.0)
            cur = a + tau * u
            j, t = jj, tau
            out[k] = cur
        return out, float(s[-1] - (s[j] + t * lengths[j]))

    lo, hi = 0.5 * s[-1] / (n - 1), s[-1] / (n - 1)  # chords never exceed the arc
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if walk(mid)[1] > 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-13 * s[-1]:
            break
    # The walk with the chord just short of the end: every step completed, every chord
    # equal to round-off, the last point within n 1e-13 of the length before the end.
    pts, left = walk(lo)
    if not left >= 0.0:
        raise RuntimeError("resample_equal_chords: the walk did not reach the end")
    return pts


def exclusion_arc_length(diameter: float) -> float:
    """Arc-length window [m] inside which pairs of centerline points are *local* (not contacts).

    Derivation: on a bend of radius R, two points an arc length a apart are a chord
    2 R sin(a / 2R) apart. The tightest bend a tube of diameter D admits has R = D/2, and on
    it the chord is below D for every a < pi D / 2 (it reaches D, diametrically opposite
    points, at a = pi D / 2). For R > D/2 the chord at a = pi D / 2 is larger than D (it
    increases with R). So pairs closer than pi D / 2 along the curve are never a genuine
    contact of a tube whose curvature is at most 2/D, and a bend of radius D/2 does not count.
    """
    return 0.5 * np.pi * diameter


def _segment_distance(p0, p1, q0, q1) -> float:
    """Minimum distance between segments [p0, p1] and [q0, q1] (clamped closest points)."""
    d1 = p1 - p0
    d2 = q1 - q0
    r = p0 - q0
    a = d1 @ d1
    e = d2 @ d2
    f = d2 @ r
    c = d1 @ r
    b = d1 @ d2
    den = a * e - b * b
    s = np.clip((b * f - c * e) / den, 0.0, 1.0) if den > 1e-300 else 0.0
    t = (b * s + f) / e if e > 0 else 0.0
    if t < 0.0:
        t = 0.0
        s = np.clip(-c / a, 0.0, 1.0) if a > 0 else 0.0
    elif t > 1.0:
        t = 1.0
        s = np.clip((b - c) / a, 0.0, 1.0) if a > 0 else 0.0
    return float(np.linalg.norm(p0 + s * d1 - q0 - t * d2))


def min_nonlocal_distance(
    points: ArrayLike, closed: bool, exclusion_arc_length: float
) -> tuple[float, float, float]:
    """Minimum distance [m] between points more than ``exclusion_arc_length`` apart along the curve.

    Returns (distance, S_a, S_b), the arc lengths [m] of the closest pair (S_a < S_b). The
    search is over vertex pairs (KD-tree, radius doubled until a non-local pair is found) and
    then refined with exact segment-segment distances on the edges around the closest pair,
    so the result is the polygon's value to within the curvature sag of one edge. Returns
    (inf, nan, nan) when no pair is non-local (a curve shorter than twice the window).
    """
    p = as_points(points)
    s = vertex_arclength(p, closed)
    length = total_length(p, closed)
    tree = cKDTree(p)
    extent = float(np.linalg.norm(np.ptp(p, axis=0))) + 1e-300
    radius = max(exclusion_arc_length, float(edge_lengths(p, closed).max()), 1e-12 * extent)
    while True:
        pairs = tree.query_pairs(radius, output_type="ndarray")
        if pairs.size:
            sep = np.abs(s[pairs[:, 0]] - s[pairs[:, 1]])
            if closed:
                sep = np.minimum(sep, length - sep)
            pairs = pairs[sep > exclusion_arc_length]
        if pairs.size or radius > extent:
            break
        radius *= 2.0
    if not pairs.size:
        return float("inf"), float("nan"), float("nan")
    d = np.linalg.norm(p[pairs[:, 0]] - p[pairs[:, 1]], axis=1)
    best = pairs[np.argmin(d)]
    lengths = edge_lengths(p, closed)
    n = p.shape[0]
    dmin = float(d.min())
    sa, sb = s[best[0]], s[best[1]]
    # Refine: the true polygon distance may lie on an edge next to the closest vertices.
    for ia in (best[0] - 1, best[0]):
        for ib in (best[1] - 1, best[1]):
            if not closed and (ia < 0 or ib < 0 or ia >= n - 1 or ib >= n - 1):
                continue
            ends_a = np.array([s[ia % n], s[ia % n] + lengths[ia % n]])
            ends_b = np.array([s[ib % n], s[ib % n] + lengths[ib % n]])
            sep = np.abs(ends_a[:, None] - ends_b[None, :])
            if closed:
                sep = np.minimum(sep, length - sep)
            if sep.min() <= exclusion_arc_length:
                continue  # edges that share a local stretch of curve are not a non-local pair
            a0, a1 = p[ia % n], p[(ia + 1) % n]
            b0, b1 = p[ib % n], p[(ib + 1) % n]
            dseg = _segment_distance(a0, a1, b0, b1)
            if dseg < dmin:
                dmin = dseg
    i, j = sorted((int(best[0]), int(best[1])))
    sa, sb = float(s[i]), float(s[j])
    return dmin, sa, sb


def max_curvature(points: ArrayLike, closed: bool) -> float:
    """Largest Bergou vertex curvature [1/m] of the polygon (see tightknot.knots.curvature)."""
    from tightknot.knots.curvature import bergou_curvature

    return float(np.max(bergou_curvature(points, closed)))


def scale_for_diameter(
    points: ArrayLike, diameter: float, closed: bool, clearance: float = 1.05
) -> NDArray[np.float64]:
    """Scale a curve about its centroid so a rod of ``diameter`` [m] along it has no overlap.

    Two conditions, each with a margin ``clearance`` >= 1:
    - non-local distance: min distance over pairs farther apart along the curve than
      :func:`exclusion_arc_length` (pi D / 2) is at least ``diameter * clearance``;
    - local bending: curvature at most 2 / (D * clearance) (bend radius >= clearance * D / 2),
      because a tube bent tighter than radius D/2 overlaps itself on the inside of the bend.
    The window is measured in the scaled curve, so the scale is found by a fixed-point
    iteration (the non-local minimum only grows as the window shrinks with a larger scale).
    Returns the scaled points (the centroid is kept).
    """
    p = as_points(points)
    if diameter <= 0 or clearance < 1.0:
        raise ValueError("diameter must be > 0 and clearance >= 1")
    c = p.mean(axis=0)
    q = p - c
    lam = diameter * clearance * max_curvature(q, closed) / 2.0
    lam = max(lam, 1e-300)
    for _ in range(50):
        d, _, _ = min_nonlocal_distance(lam * q, closed, exclusion_arc_length(diameter))
        if not np.isfinite(d) or d >= diameter * clearance * (1 - 1e-9):
            break
        if d <= 0:
            raise ValueError("curve intersects itself: it cannot be scaled to avoid overlap")
        lam *= diameter * clearance / d
    return c + lam * q


def check_no_overlap(points: ArrayLike, diameter: float, closed: bool) -> None:
    """Raise ValueError, saying where, if a rod of ``diameter`` [m] on the curve self-overlaps."""
    d, sa, sb = min_nonlocal_distance(points, closed, exclusion_arc_length(diameter))
    if d < diameter:
        raise ValueError(
            f"centerline overlaps itself: points at arc length S = {sa:.6g} and {sb:.6g} "
            f"are {d:.6g} apart, less than the rod diameter {diameter:.6g}"
        )
