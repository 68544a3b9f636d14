"""Measurements on a converged FEM state: contact forces, pressures, patch sizes, areas.

Pure functions of positions, forces and meshes (they never solve). Pressures are true
(Cauchy) contact pressures: nodal contact force over the node's deformed surface weight.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .contact import PenaltyContact
from .mesh import lumped_face_weights, polygon_area


def contact_nodal(contact: PenaltyContact, x: np.ndarray, faces: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Forces on the rigid body (m, dim) [N] and true pressures (m,) [Pa] of the contact
    nodes, from the current positions ``x`` (npoints, dim) of all points; ``faces`` are
    the lateral faces that carry the contact nodes' surface weights."""
    force, _, _, _ = contact.evaluate(x[contact.points])
    deformed = lumped_face_weights(x, faces)[contact.points]
    magnitude = np.linalg.norm(force, axis=1)
    pressure = np.divide(magnitude, deformed, out=np.zeros_like(magnitude), where=deformed > 0)
    return force, pressure


def edge_position(s: np.ndarray, p: np.ndarray) -> float:
    """Edge b [m] of a contact along a line of nodes at positions ``s`` from its centre.

    ``s`` ascending from the centre (s[0] = 0), ``p`` the pressures there. Near the edge
    of a smooth (Hertz-like) contact p^2 is linear in the distance to the edge
    (p = p0 sqrt(1 - s^2/b^2), Johnson 1985 eq. 4.44), so b is extrapolated from the last
    two loaded nodes and clamped between the last loaded and the first free node. With a
    single loaded node, b is half the first spacing (mid-point rule).
    """
    loaded = np.nonzero(p > 0.0)[0]
    if loaded.size == 0:
        return 0.0
    k = int(loaded.max())
    if k + 1 >= len(s):
        return float(s[k])
    if k == 0:
        return float(0.5 * s[1])
    p1, p2 = p[k - 1] ** 2, p[k] ** 2
    if p1 <= p2:  # pressure not falling toward the edge: take the mid-point
        return float(0.5 * (s[k] + s[k + 1]))
    b = s[k] + p2 / (p1 - p2) * (s[k] - s[k - 1])
    return float(np.clip(b, s[k], s[k + 1]))


def line_profile(contact: PenaltyContact, x: np.ndarray, pressure: np.ndarray,
                 select: np.ndarray, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Positions along ``axis`` [m] (ascending) and pressures [Pa] of the contact nodes
    selected by the boolean mask ``select`` (over the contact nodes)."""
    s = x[contact.points[select], axis]
    order = np.argsort(s)
    return s[order], pressure[select][order]


def section_area(points_2d: np.ndarray, quads: np.ndarray) -> float:
    """Area [m^2] of a section meshed by ``quads`` with 2D coordinates ``points_2d``."""
    return polygon_area(points_2d, quads)


def boundary_length(points_2d: np.ndarray, edges: np.ndarray) -> float:
    """Length [m] of the polyline ``edges`` with 2D coordinates ``points_2d``."""
    return float(np.linalg.norm(points_2d[edges[:, 1]] - points_2d[edges[:, 0]], axis=1).sum())


def volume_ratio(solid: Any) -> float:
    """Deformed over undeformed volume [-] of a FElupe nearly incompressible solid."""
    dv = solid.field.region.dV * np.linalg.det(solid.field.extract()[0].T).T
    return float(dv.sum() / solid.field.region.dV.sum())
