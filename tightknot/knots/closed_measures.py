"""Measures of a closed knot: barycenter, laying flat, rho(s), z(s), inner and outer segments.

Definitions of Johanns et al. 2021 (physics.md sec. 2): G = sum_i r_i ds_i / L; the knot placed
flat in the x-y plane with its 3-fold axis along e_z and G on the z axis; rho = sqrt(X^2 + Y^2)
/ D0 and z = Z / D0; s = S / L * L0 / D0 with its origin at a point of the 3-fold symmetry.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from tightknot.knots._arclength import total_length, vertex_arclength, vertex_weights


def barycenter(points: NDArray[np.float64], closed: bool = True) -> NDArray[np.float64]:
    """G = sum_i r_i ds_i / L [m], ds_i the Voronoi length of vertex i (Johanns et al. 2021)."""
    w = vertex_weights(points, closed)
    return (w[:, None] * points).sum(axis=0) / w.sum()


def threefold_axis(points: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray]:
    """Unit 3-fold axis of a closed trefoil-like curve, and the three spreads [m^2].

    The length-weighted second-moment tensor about G of a body with 3-fold rotational symmetry
    is transversely isotropic: the symmetry axis is one eigenvector, the other two eigenvalues
    are equal. A trefoil is flat (its height is about D while its radius is about 1.5 D), so
    the axis is the eigenvector of the *smallest* spread; the two in-plane spreads are
    returned so a caller can check they are nearly equal (a large difference means the knot
    is far from 3-fold symmetric and the axis is ill-defined).

    Sign convention: e_z points so the curve turns counter-clockwise about it, i.e. the
    signed area sum (X dY - Y dX) is positive. This is independent of the frame the data
    come in, so z(s) of a rotated knot is identical; reversing the curve's direction or
    mirroring it flips z.
    """
    g = barycenter(points)
    q = points - g
    w = vertex_weights(points, True)
    m = (w[:, None, None] * q[:, :, None] * q[:, None, :]).sum(axis=0) / w.sum()
    vals, vecs = np.linalg.eigh(m)
    axis = vecs[:, 0]
    dq = np.roll(q, -1, axis=0) - q
    turning = np.einsum("ij,ij->i", np.cross(q, dq), np.broadcast_to(axis, q.shape)).sum()
    if turning < 0:
        axis = -axis
    return axis, vals


def lay_flat(points: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray, NDArray]:
    """Coordinates (X, Y, Z) [m] of the knot with G at the origin and the 3-fold axis along e_z.

    Returns (XYZ (N, 3), axis (3,) in the input frame, barycenter G (3,) in the input frame).
    The in-plane orientation is arbitrary here; :func:`closed_knot_profile` fixes X toward
    the origin of s.
    """
    g = barycenter(points)
    axis, _ = threefold_axis(points)
    trial = np.eye(3)[int(np.argmin(np.abs(axis)))]
    ex = trial - (trial @ axis) * axis
    ex /= np.linalg.norm(ex)
    ey = np.cross(axis, ex)
    frame = np.stack([ex, ey, axis])
    return (points - g) @ frame.T, axis, g


def _threefold_phase(s: NDArray, rho: NDArray, length: float) -> float:
    """Phase of the third Fourier harmonic of rho(S): S of its first maximum in [0, L/3)."""
    w = 2.0 * np.pi * 3.0 / length
    # Periodic Voronoi weights ds_i (the rectangle rule is spectrally exact for periodic data).
    nxt = np.diff(np.append(s, length))
    ds = 0.5 * (nxt + np.roll(nxt, 1))
    c = float(np.sum(rho * np.cos(w * s) * ds))
    d = float(np.sum(rho * np.sin(w * s) * ds))
    phase = np.arctan2(d, c)  # rho ~ a cos(w S - phase)
    return float((phase / w) % (length / 3.0))


def _refine_extremum(s: NDArray, f: NDArray, s0: float, half: float, length: float,
                     find_max: bool) -> float:
    """Arc length of the extremum of f within |S - s0| <= half (periodic), parabola-refined."""
    sep = (s - s0 + 0.5 * length) % length - 0.5 * length
    idx = np.nonzero(np.abs(sep) <= half)[0]
    k = idx[np.argmax(f[idx]) if find_max else np.argmin(f[idx])]
    n = s.size
    fm, f0, fp = f[(k - 1) % n], f[k], f[(k + 1) % n]
    den = fm - 2 * f0 + fp
    shift = 0.5 * (fm - fp) / den if den != 0 else 0.0
    ds = 0.5 * ((s[(k + 1) % n] - s[k]) % length + (s[k] - s[(k - 1) % n]) % length)
    return float((s[k] + np.clip(shift, -1, 1) * ds) % length)


def closed_knot_profile(
    points: NDArray[np.float64], diameter: float, rest_length: float | None = None
) -> dict[str, object]:
    """rho(s), z(s), X(s), Y(s), origin, inner/outer segments of a closed (trefoil) knot.

    ``diameter`` = D0 [m]; ``rest_length`` = L0 [m] (default: the current length L).
    Origin of s: the 3-fold symmetric knot has 2-fold axes through the middles of its outer
    and inner segments (its symmetry group is D3); s = 0 is put at the middle of an outer
    segment, found as the maximum of rho(S) near a maximum of the third Fourier harmonic of
    rho(S) (robust to noise); of the three, the first along the vertex numbering. Outer
    (inner) segments are the three local maxima (minima) of rho within L/6 of the harmonic's
    maxima (minima).
    Arrays are returned ordered by s in [-L0/(2 D0), L0/(2 D0)).
    """
    length = total_length(points, True)
    l0 = length if rest_length is None else float(rest_length)
    xyz, axis, g = lay_flat(points)
    S = vertex_arclength(points, True)
    rho_raw = np.hypot(xyz[:, 0], xyz[:, 1])
    phase = _threefold_phase(S, rho_raw, length)
    third = length / 3.0
    outer = [_refine_extremum(S, rho_raw, phase + k * third, length / 6, length, True)
             for k in range(3)]
    inner = [_refine_extremum(S, rho_raw, phase + (k + 0.5) * third, length / 6, length, False)
             for k in range(3)]
    # The three outer middles are equivalent by symmetry; taking the largest rho would
    # flip between them with round-off on a symmetric knot, so take the first one along the
    # vertex numbering (stable under rotation; a cyclic shift moves s = 0 to an equivalent one).
    origin = min(outer)
    # In-plane orientation: X axis toward the origin point (rotation about e_z only).
    px, py = np.interp(origin, S, xyz[:, 0], period=length), np.interp(origin, S, xyz[:, 1],
                                                                     period=length)
    ang = np.arctan2(py, px)
    c, sn = np.cos(ang), np.sin(ang)
    X = c * xyz[:, 0] + sn * xyz[:, 1]
    Y = -sn * xyz[:, 0] + c * xyz[:, 1]
    scale = l0 / (length * diameter)  # s = S / L * L0 / D0
    half = 0.5 * l0 / diameter
    s = ((S - origin) * scale + half) % (2 * half) - half
    order = np.argsort(s, kind="stable")

    def to_s(values: list[float]) -> list[float]:
        return sorted(float(((v - origin) * scale + half) % (2 * half) - half) for v in values)

    _, spreads = threefold_axis(points)
    return {
        "order": order,
        "s": s[order],
        "rho": rho_raw[order] / diameter,
        "z": xyz[order, 2] / diameter,
        "X_over_D0": X[order] / diameter,
        "Y_over_D0": Y[order] / diameter,
        "origin_S": float(origin),
        "axis": axis,
        "barycenter": g,
        "inplane_spread_ratio": float(spreads[2] / spreads[1]),
        "outer_segments_s": to_s(outer),
        "inner_segments_s": to_s(inner),
    }
