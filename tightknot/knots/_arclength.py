"""Arc-length bookkeeping for polygonal curves (shared helpers, SI units in, SI units out).

A curve is an ``(N, 3)`` array of vertex positions [m]. A *closed* curve has an implicit edge
from the last vertex back to the first (the first vertex is not repeated); an *open* curve has
``N - 1`` edges.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def as_points(points: ArrayLike, min_points: int = 2) -> NDArray[np.float64]:
    """Validate and return ``points`` as a float64 ``(N, 3)`` array [m]."""
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"points must have shape (N, 3), got {p.shape}")
    if p.shape[0] < min_points:
        raise ValueError(f"need at least {min_points} points, got {p.shape[0]}")
    if not np.all(np.isfinite(p)):
        raise ValueError("points contain NaN or inf")
    return p


def edges(points: NDArray[np.float64], closed: bool) -> NDArray[np.float64]:
    """Edge vectors e_i = r_{i+1} - r_i [m]; shape (N, 3) if closed, (N - 1, 3) if open."""
    if closed:
        return np.roll(points, -1, axis=0) - points
    return np.diff(points, axis=0)


def edge_lengths(points: NDArray[np.float64], closed: bool) -> NDArray[np.float64]:
    """Edge lengths |e_i| [m]."""
    return np.linalg.norm(edges(points, closed), axis=1)


def vertex_arclength(points: NDArray[np.float64], closed: bool) -> NDArray[np.float64]:
    """Arc length S_i [m] of each vertex from vertex 0 along the polygon, shape (N,)."""
    lengths = edge_lengths(points, closed)
    s = np.zeros(points.shape[0])
    s[1:] = np.cumsum(lengths[: points.shape[0] - 1])
    return s


def total_length(points: NDArray[np.float64], closed: bool) -> float:
    """Total polygon length L [m] (including the closing edge for a closed curve)."""
    return float(edge_lengths(points, closed).sum())


def vertex_weights(points: NDArray[np.float64], closed: bool) -> NDArray[np.float64]:
    """Length ds_i [m] attributed to each vertex: half of each adjacent edge (sum = L)."""
    lengths = edge_lengths(points, closed)
    w = np.zeros(points.shape[0])
    if closed:
        w = 0.5 * (lengths + np.roll(lengths, 1))
    else:
        w[:-1] += 0.5 * lengths
        w[1:] += 0.5 * lengths
    return w


def arc_separation(
    s_a: NDArray[np.float64], s_b: NDArray[np.float64], length: float, closed: bool
) -> NDArray[np.float64]:
    """Distance along the curve [m] between arc lengths s_a and s_b (the shorter way if closed)."""
    d = np.abs(np.asarray(s_a) - np.asarray(s_b))
    if closed:
        d = np.minimum(d, length - d)
    return d


def resample_uniform(points: ArrayLike, n: int, closed: bool) -> NDArray[np.float64]:
    """Resample a polygon to ``n`` vertices equally spaced in arc length [m].

    Linear interpolation along the polygon. Closed: periodic, the first vertex is kept and
    the spacing is L/n. Open: both end points are kept and the spacing is L/(n - 1).
    """
    p = as_points(points)
    if n < (3 if closed else 2):
        raise ValueError(f"n must be at least {3 if closed else 2}, got {n}")
    q = np.vstack([p, p[:1]]) if closed else p
    lengths = edge_lengths(q, closed=False)
    if np.any(lengths == 0):
        keep = np.concatenate([[True], lengths > 0])
        q = q[keep]
        lengths = lengths[lengths > 0]
    s = np.concatenate([[0.0], np.cumsum(lengths)])
    targets = np.linspace(0.0, s[-1], n, endpoint=not closed)
    return np.stack([np.interp(targets, s, q[:, d]) for d in range(3)], axis=1)
