"""Reference and material frames in NumPy (initial frames, measurements, the test oracle).

The Warp kernels in :mod:`tightknot.rods.elastic_kernels` do the per-iteration transport;
these vectorised functions build the first frames and the material frames for output.
"""

from __future__ import annotations

import numpy as np


def parallel_transport(u: np.ndarray, t1: np.ndarray, t2: np.ndarray) -> np.ndarray:
    """Transport vectors ``u`` from unit tangents ``t1`` to ``t2`` (rows), Bergou 2008 sec. 4.1.

    The rotation about ``t1 x t2`` that takes ``t1`` onto ``t2``; identity where they are
    parallel.
    """
    u, t1, t2 = np.atleast_2d(u), np.atleast_2d(t1), np.atleast_2d(t2)
    b = np.cross(t1, t2)
    nb = np.linalg.norm(b, axis=1)
    out = u.copy()
    ok = nb > 1e-14
    if ok.any():
        bh = b[ok] / nb[ok, None]
        n1 = np.cross(t1[ok], bh)
        n2 = np.cross(t2[ok], bh)
        uu = u[ok]
        out[ok] = (
            np.einsum("ij,ij->i", uu, t1[ok])[:, None] * t2[ok]
            + np.einsum("ij,ij->i", uu, n1)[:, None] * n2
            + np.einsum("ij,ij->i", uu, bh)[:, None] * bh
        )
    return out


def signed_angle(u: np.ndarray, v: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Signed angle from ``u`` to ``v`` about ``axis`` (rows) [rad], in (-pi, pi]."""
    return np.arctan2(np.einsum("ij,ij->i", np.cross(u, v), axis), np.einsum("ij,ij->i", u, v))


def any_perpendicular(t: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to unit vector ``t`` (3,)."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(t[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    d = helper - helper.dot(t) * t
    return d / np.linalg.norm(d)


def space_parallel_frames(tangents: np.ndarray) -> np.ndarray:
    """Reference directors d1 of consecutive unit ``tangents`` (E, 3) by space-parallel
    transport from an arbitrary director of the first edge (zero reference twist)."""
    d1 = np.empty_like(tangents)
    d1[0] = any_perpendicular(tangents[0])
    for j in range(1, tangents.shape[0]):
        d = parallel_transport(d1[j - 1], tangents[j - 1], tangents[j])[0]
        d -= d.dot(tangents[j]) * tangents[j]
        d1[j] = d / np.linalg.norm(d)
    return d1


def reference_twist(d1: np.ndarray, t: np.ndarray, joint_edge: np.ndarray) -> np.ndarray:
    """Reference twist at each joint [rad] in (-pi, pi] (Bergou 2010 sec. 4.2)."""
    a, b = joint_edge[:, 0], joint_edge[:, 1]
    u = parallel_transport(d1[a], t[a], t[b])
    return signed_angle(u, d1[b], t[b])


def material_frames(
    d1_ref: np.ndarray, t: np.ndarray, theta: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Material directors (m1, m2) of each edge: the reference frame rotated by theta."""
    d2 = np.cross(t, d1_ref)
    c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
    m1 = c * d1_ref + s * d2
    m2 = -s * d1_ref + c * d2
    return m1, m2
