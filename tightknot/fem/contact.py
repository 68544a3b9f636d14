"""Frictionless node-to-rigid-surface penalty contact with a smoothed, area-weighted law.

Each potential contact node a carries the reference surface weight A_a (integral of its
shape function over the lateral surface, m^2 in 3D, m per unit depth in plane strain)
and the energy A_a phi(pen_a), pen_a = -g(x_a) the penetration into the rigid body.
phi is a C2 penalty (cubic onset over a smoothing depth g0, then quadratic):

    phi'(pen) = eps pen^2 / (2 g0)      for 0 < pen < g0,
    phi'(pen) = eps (pen - g0 / 2)      for pen >= g0,

so phi' is the nominal contact pressure [Pa] and eps [Pa/m] the penalty stiffness per
unit area. Weighting by A_a makes the pressure independent of the mesh grading (a plain
nodal penalty is not), and the smooth onset stops the active set from chattering when a
node crosses the surface (the issue a scout met with crossing contact on a coarse mesh).

Residual (internal force) r_a = dPhi/dx_a = -A_a phi' n_a and stiffness
K_a = A_a (phi'' n n^T - phi' H) with n = grad g, H = grad grad g: the exact Hessian of
the penalty energy (Wriggers, "Computational Contact Mechanics", 2006, sec. 4.2).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class RigidPlane:
    """Rigid plane through ``point`` [m] with unit outward normal ``normal`` (into the
    solid's side). ``shift`` [m] is the prescribed rigid translation."""

    point: np.ndarray
    normal: np.ndarray
    shift: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def gap(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Signed gaps g [m] (negative inside), normals n = grad g, Hessians (None)."""
        dim = x.shape[1]
        n = np.asarray(self.normal, dtype=float)[:dim]
        n = n / np.linalg.norm(n)
        origin = (np.asarray(self.point, dtype=float) + self.shift)[:dim]
        return (x - origin) @ n, np.broadcast_to(n, x.shape), None


@dataclass
class RigidCylinder:
    """Rigid cylinder of radius ``radius`` [m] about the line through ``center`` along
    ``axis``; the solid lies outside it. ``shift`` [m] is the prescribed translation."""

    center: np.ndarray
    axis: np.ndarray
    radius: float
    shift: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def gap(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Signed gaps g = |x_perp| - R [m], normals n and Hessians H = (I - aa - nn)/|x_perp|."""
        a = np.asarray(self.axis, dtype=float)
        a = a / np.linalg.norm(a)
        d = x - (np.asarray(self.center, dtype=float) + self.shift)
        d_perp = d - np.outer(d @ a, a)
        dist = np.linalg.norm(d_perp, axis=1)
        n = d_perp / dist[:, None]
        eye = np.eye(3) - np.outer(a, a)
        hess = (eye[None] - np.einsum("ai,aj->aij", n, n)) / dist[:, None, None]
        return dist - self.radius, n, hess


@dataclass
class PenaltyContact:
    """Penalty contact of the nodes ``points`` (indices) with a rigid ``surface``.

    ``weights`` [m^2 or m] are the reference surface weights of those nodes,
    ``stiffness`` eps [Pa/m] the penalty per unit area, ``smoothing`` g0 [m] the onset depth.
    """

    surface: RigidPlane | RigidCylinder
    points: np.ndarray
    weights: np.ndarray
    stiffness: float
    smoothing: float

    def pressure_law(self, pen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nominal pressure phi'(pen) [Pa] and its slope phi''(pen) [Pa/m]."""
        eps, g0 = self.stiffness, self.smoothing
        pen = np.maximum(pen, 0.0)
        onset = pen < g0
        p = np.where(onset, eps * pen**2 / (2.0 * g0), eps * (pen - 0.5 * g0))
        dp = np.where(onset, eps * pen / g0, eps)
        return p, dp

    def evaluate(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Residual forces (m, dim) [N], stiffness blocks (m, dim, dim) [N/m], nominal
        pressures (m,) [Pa] and outward normals (m, dim) at current positions ``x`` of
        the contact nodes (m, dim) [m]."""
        g, n, hess = self.surface.gap(x)
        p, dp = self.pressure_law(-g)
        w = self.weights
        force = -(w * p)[:, None] * n
        blocks = (w * dp)[:, None, None] * np.einsum("ai,aj->aij", n, n)
        if hess is not None:
            dim = x.shape[1]
            blocks -= (w * p)[:, None, None] * hess[:, :dim, :dim]
        return force, blocks, p, np.asarray(n)
