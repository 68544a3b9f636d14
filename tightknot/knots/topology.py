"""Knot type of a closed polygon: Alexander polynomial and knot determinant.

Method (Alexander 1928; as in Livingston, *Knot Theory*, 1993, ch. 6): project the polygon
onto a generic plane, find its crossings, split the curve into arcs at the under-passages,
write one row of the Alexander matrix per crossing, and take the determinant of a
(n - 1) x (n - 1) minor. The determinant at t = -1 is computed exactly with integers
(fraction-free Bareiss elimination); the polynomial coefficients are decoded exactly from
one integer evaluation at a large base (Kronecker substitution), so no floating point enters
the invariant.

The projection direction is a seeded random rotation; a projection is rejected (and the next
seeded rotation tried) when a crossing falls too close to a vertex, two projected edges are
nearly parallel where they cross, or the two strands at a crossing are nearly at the same
height (a near self-intersection of the 3D curve). Among the accepted projections of the
first few tries, the one with the fewest crossings is used, to keep the matrix small.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from tightknot.knots._arclength import as_points
from tightknot.knots.knot_table import knot_name

# A crossing closer than this fraction of an edge to a vertex makes the projection ambiguous
# (the crossing could belong to either edge after round-off): reject the projection.
_VERTEX_MARGIN = 1e-6
# |sin| of the angle between projected edges below this: near-tangency, reject.
_MIN_SIN = 1e-8
# Strand height difference below this fraction of the curve size: near self-intersection.
_MIN_DZ = 1e-10


class TopologyError(ValueError):
    """The knot type cannot be decided (no generic projection found)."""


@numba.njit(cache=True)
def _find_crossings(xy: np.ndarray, order: np.ndarray, xmin: np.ndarray, xmax: np.ndarray,
                    ymin: np.ndarray, ymax: np.ndarray, n_edges: int, closed_n: int):
    """Sweep over edges sorted by xmin; return (i, j, ti, tj, flag) for crossing edge pairs.

    flag = 1 marks a degenerate configuration (crossing near a vertex or near-parallel edges).
    Adjacent edges (sharing a vertex) are skipped: they meet only at that vertex.
    """
    out_i = []
    out_j = []
    out_ti = []
    out_tj = []
    degenerate = 0
    for a in range(n_edges):
        i = order[a]
        for b in range(a + 1, n_edges):
            j = order[b]
            if xmin[j] > xmax[i]:
                break
            if ymin[j] > ymax[i] or ymax[j] < ymin[i]:
                continue
            d = abs(i - j)
            if d == 1 or d == closed_n - 1:
                continue
            i1 = (i + 1) % closed_n
            j1 = (j + 1) % closed_n
            px = xy[i, 0]
            py = xy[i, 1]
            rx = xy[i1, 0] - px
            ry = xy[i1, 1] - py
            qx = xy[j, 0]
            qy = xy[j, 1]
            sx = xy[j1, 0] - qx
            sy = xy[j1, 1] - qy
            den = rx * sy - ry * sx
            lr = np.sqrt(rx * rx + ry * ry)
            ls = np.sqrt(sx * sx + sy * sy)
            wx = qx - px
            wy = qy - py
            if abs(den) <= _MIN_SIN * lr * ls:
                # Nearly parallel: degenerate only if the edges are also nearly collinear.
                if abs(wx * ry - wy * rx) <= 1e-9 * (lr * lr + ls * ls + wx * wx + wy * wy):
                    degenerate = 1
                continue
            ti = (wx * sy - wy * sx) / den
            tj = (wx * ry - wy * rx) / den
            if ti < -_VERTEX_MARGIN or ti > 1 + _VERTEX_MARGIN:
                continue
            if tj < -_VERTEX_MARGIN or tj > 1 + _VERTEX_MARGIN:
                continue
            if (ti < _VERTEX_MARGIN or ti > 1 - _VERTEX_MARGIN or tj < _VERTEX_MARGIN
                    or tj > 1 - _VERTEX_MARGIN):
                degenerate = 1
                continue
            out_i.append(i)
            out_j.append(j)
            out_ti.append(ti)
            out_tj.append(tj)
    return out_i, out_j, out_ti, out_tj, degenerate


def _crossings(points: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray, NDArray] | None:
    """Crossings of the projection on the x-y plane, or None if the projection is degenerate.

    Returns per crossing: over position, under position (edge index + fraction along it),
    and the sign (+1 right-handed, -1 left-handed; viewer on the +z side).
    """
    n = points.shape[0]
    xy = np.ascontiguousarray(points[:, :2])
    nxt = np.roll(xy, -1, axis=0)
    lo = np.minimum(xy, nxt)
    hi = np.maximum(xy, nxt)
    order = np.argsort(lo[:, 0], kind="stable")
    ii, jj, ti, tj, deg = _find_crossings(xy, order, lo[:, 0].copy(), hi[:, 0].copy(),
                                          lo[:, 1].copy(), hi[:, 1].copy(), n, n)
    if deg:
        return None
    ii = np.asarray(ii, dtype=np.int64)
    jj = np.asarray(jj, dtype=np.int64)
    ti = np.asarray(ti, dtype=np.float64)
    tj = np.asarray(tj, dtype=np.float64)
    if ii.size == 0:
        e = np.zeros(0)
        return e, e, e, e
    z = points[:, 2]
    zn = np.roll(z, -1)
    zi = z[ii] + ti * (zn[ii] - z[ii])
    zj = z[jj] + tj * (zn[jj] - z[jj])
    size = float(np.ptp(points, axis=0).max())
    if np.any(np.abs(zi - zj) <= _MIN_DZ * size):
        return None
    pos_i = ii + ti
    pos_j = jj + tj
    i_over = zi > zj
    over = np.where(i_over, pos_i, pos_j)
    under = np.where(i_over, pos_j, pos_i)
    e2 = nxt - xy
    d_over = np.where(i_over[:, None], e2[ii], e2[jj])
    d_under = np.where(i_over[:, None], e2[jj], e2[ii])
    # Right-handed (positive) crossing: (d_over x d_under) . e_z > 0 seen from above.
    cross = d_over[:, 0] * d_under[:, 1] - d_over[:, 1] * d_under[:, 0]
    sign = np.sign(cross)
    allpos = np.concatenate([over, under])
    if np.unique(np.round(allpos, 12)).size != allpos.size:
        return None  # two crossings on one edge at the same place: not generic
    return over, under, sign, pos_i


def _alexander_rows(
    over: NDArray, under: NDArray, sign: NDArray
) -> list[tuple[int, int, int, int]]:
    """Per crossing: (over arc, incoming under arc, outgoing under arc, sign).

    Arcs are numbered by the under-passage that starts them: arc k runs from the k-th
    under-passage (in order along the curve) to the next one.
    """
    n = under.size
    order = np.argsort(under)
    u_sorted = under[order]
    rows = []
    for rank, c in enumerate(order):
        out_arc = rank
        in_arc = (rank - 1) % n
        # Arc containing the over-passage: the last under-passage before it (cyclically).
        k = int(np.searchsorted(u_sorted, over[c])) - 1
        over_arc = k % n
        rows.append((over_arc, in_arc, out_arc, int(sign[c])))
    return rows


def _matrix_at(rows: list[tuple[int, int, int, int]], t: int) -> list[list[int]]:
    """Integer Alexander matrix evaluated at integer t (Livingston 1993, sec. 6.2).

    Row of a crossing: 1 - t on the over arc; for a positive crossing t on the incoming and
    -1 on the outgoing under arc, swapped for a negative crossing. Entries on a shared arc add.
    """
    n = len(rows)
    m = [[0] * n for _ in range(n)]
    for r, (o, a_in, a_out, sgn) in enumerate(rows):
        m[r][o] += 1 - t
        if sgn > 0:
            m[r][a_in] += t
            m[r][a_out] += -1
        else:
            m[r][a_in] += -1
            m[r][a_out] += t
    return m


def _bareiss_det(m: list[list[int]]) -> int:
    """Exact determinant of an integer matrix (fraction-free Bareiss elimination)."""
    a = [row[:] for row in m]
    n = len(a)
    if n == 0:
        return 1
    sign = 1
    prev = 1
    for k in range(n - 1):
        if a[k][k] == 0:
            swap = next((r for r in range(k + 1, n) if a[r][k] != 0), None)
            if swap is None:
                return 0
            a[k], a[swap] = a[swap], a[k]
            sign = -sign
        akk = a[k][k]
        for i in range(k + 1, n):
            aik = a[i][k]
            row_i = a[i]
            row_k = a[k]
            for j in range(k + 1, n):
                row_i[j] = (row_i[j] * akk - aik * row_k[j]) // prev
        prev = akk
    return sign * a[n - 1][n - 1]


def _minor(m: list[list[int]]) -> list[list[int]]:
    """Delete the last row and column (any (n-1) minor gives Delta up to a unit +-t^k)."""
    return [row[:-1] for row in m[:-1]]


def _project(points: NDArray[np.float64], seed: int, tries: int):
    """Rows of the first generic projections among ``tries`` seeded rotations (fewest crossings)."""
    rng = np.random.default_rng(seed)
    best = None
    accepted = 0
    centred = points - points.mean(axis=0)
    for _ in range(tries):
        rot = Rotation.random(random_state=rng).as_matrix()
        res = _crossings(centred @ rot.T)
        if res is None:
            continue
        over, under, sign, _ = res
        rows = _alexander_rows(over, under, sign) if under.size else []
        if best is None or len(rows) < len(best):
            best = rows
        accepted += 1
        if accepted >= 3:
            break
    if best is None:
        raise TopologyError(
            f"no generic projection found in {tries} random rotations: the polygon is nearly "
            "self-intersecting (strands closer than 1e-10 of its size) or has repeated vertices"
        )
    return best


def _check(points: ArrayLike) -> NDArray[np.float64]:
    p = as_points(points, min_points=3)
    if np.any(np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1) == 0):
        raise ValueError("closed polygon has repeated consecutive vertices")
    return p


def alexander_at_minus1(points: ArrayLike, seed: int = 0, tries: int = 20) -> int:
    """Knot determinant |Delta(-1)| of the closed polygon ``points`` (N, 3) [any length unit].

    1 for the unknot, 3 for the trefoil (either handedness), 5 for the figure-eight knot.
    Exact: integer arithmetic on the Alexander matrix at t = -1.
    """
    rows = _project(_check(points), seed, tries)
    if len(rows) <= 1:
        return 1
    return abs(_bareiss_det(_minor(_matrix_at(rows, -1))))


def alexander_polynomial(points: ArrayLike, seed: int = 0, tries: int = 20) -> list[int]:
    """Alexander polynomial coefficients of the closed polygon ``points`` (N, 3).

    Normalised: the factor +-t^k is removed so the lowest power is t^0, the list is symmetric
    (Delta(t) = Delta(1/t) up to that factor), and the leading coefficient is positive.
    Examples: unknot [1]; trefoil [1, -1, 1]; figure-eight [1, -3, 1].
    """
    rows = _project(_check(points), seed, tries)
    n = len(rows)
    if n <= 1:
        return [1]
    # Kronecker substitution: each row of the matrix has coefficient l1-norm <= 4, so every
    # coefficient of the (n-1) minor's determinant is below 4^(n-1) in magnitude (Hadamard-type
    # bound on the l1 norms). Evaluating at t = B > 2 * 4^(n-1) lets the balanced base-B
    # digits of det(M(B)) be read off as the coefficients, exactly.
    base = 2 * 4 ** (n - 1) + 1
    value = _bareiss_det(_minor(_matrix_at(rows, base)))
    coeffs = []
    while value != 0:
        digit = value % base
        if digit > base // 2:
            digit -= base
        coeffs.append(digit)
        value = (value - digit) // base
    if not coeffs:
        raise TopologyError("Alexander determinant vanished: degenerate diagram")
    while coeffs[0] == 0:
        coeffs.pop(0)
    if coeffs[-1] < 0:
        coeffs = [-c for c in coeffs]
    return coeffs


def knot_type(points: ArrayLike, seed: int = 0) -> str:
    """Knot type of a closed polygon, named from its Alexander polynomial by the table of
    the knots through 8 crossings (:func:`tightknot.knots.knot_table.knot_name`): "5_2";
    the candidates joined by "|" where the polynomial does not separate them
    ("8_20|3_1#3_1"); "unknown(det=..)" outside the table. Chirality-blind, and "0_1"
    means Delta = 1 (some nontrivial knots have it)."""
    return knot_name(alexander_polynomial(points, seed=seed))


def close_open_curve(
    points: ArrayLike, far_factor: float = 10.0, method: str = "axis", n_arc: int = 32
) -> NDArray[np.float64]:
    """Close an open curve (N, 3) [m] through a far-away arc, for knot typing.

    ``method="axis"``: the first end is extended straight along -u and the last along +u, with
    u the unit end-to-end direction (the pull axis of an open knot with straight tails), by
    ``far_factor`` times the curve's radius R about its centroid. ``method="radial"``: each end is
    extended radially away from the centroid instead. The two far points are then joined by
    a path that first moves radially out to a sphere of radius ``far_factor * R`` and then
    follows great circles on that sphere through a direction perpendicular to both far points;
    every point of that path lies farther than R from the centroid, so it cannot meet the
    knotted part. Returns the closed polygon (original points first, then the closure).
    """
    p = as_points(points, min_points=2)
    c = p.mean(axis=0)
    radius = float(np.linalg.norm(p - c, axis=1).max())
    big = far_factor * radius
    if method == "axis":
        u = p[-1] - p[0]
        nu = np.linalg.norm(u)
        if nu < 1e-12 * max(radius, 1e-300):
            raise ValueError("open curve ends coincide: use method='radial'")
        u = u / nu
        d_start, d_end = -u, u
    elif method == "radial":
        d_start = p[0] - c
        d_end = p[-1] - c
        for d in (d_start, d_end):
            if np.linalg.norm(d) == 0:
                raise ValueError("an end sits at the centroid: use method='axis'")
        d_start = d_start / np.linalg.norm(d_start)
        d_end = d_end / np.linalg.norm(d_end)
    else:
        raise ValueError(f"method must be 'axis' or 'radial', got {method!r}")
    f_end = p[-1] + big * d_end
    f_start = p[0] + big * d_start
    r_sphere = max(np.linalg.norm(f_end - c), np.linalg.norm(f_start - c)) * 1.01
    a = (f_end - c) / np.linalg.norm(f_end - c)
    b = (f_start - c) / np.linalg.norm(f_start - c)
    # A waypoint perpendicular to both far directions keeps each great-circle leg <= 90 deg
    # and well defined even when a and b are antipodal.
    w = np.cross(a, b)
    if np.linalg.norm(w) < 1e-6:
        trial = np.eye(3)[np.argmin(np.abs(a))]
        w = np.cross(a, trial)
    w /= np.linalg.norm(w)

    def slerp(x: NDArray, y: NDArray, k: int) -> NDArray:
        ang = np.arccos(np.clip(x @ y, -1.0, 1.0))
        ts = np.linspace(0.0, 1.0, k)[1:-1] if k > 2 else np.zeros(0)
        return np.array([(np.sin((1 - t) * ang) * x + np.sin(t * ang) * y) / np.sin(ang)
                         for t in ts]).reshape(-1, 3)

    path = [f_end, c + r_sphere * a, *(c + r_sphere * slerp(a, w, n_arc)), c + r_sphere * w,
            *(c + r_sphere * slerp(w, b, n_arc)), c + r_sphere * b, f_start]
    return np.vstack([p, np.asarray(path)])


def curve_knot_type(points: ArrayLike, closed: bool) -> str:
    """Knot type of a centerline (N, 3) [m] (an open one closed by a far-away arc,
    :func:`close_open_curve`); "undefined" when no projection of it is generic (strands
    within 1e-10 of its size: it passes through itself, or nearly), which a topology check
    then reports as a change."""
    pts = points if closed else close_open_curve(points)
    try:
        return knot_type(pts)
    except TopologyError:
        return "undefined (the curve nearly passes through itself)"
