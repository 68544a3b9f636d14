"""Structured meshes of a rod: a graded quarter disk and its extrusion along the axis.

Coordinates: the rod axis is e_z, its cross-section lies in the x-y plane, the section
centroid at rest is the origin. Quarter models use the symmetry planes x = 0 and y = 0;
3D models add z = 0 (mid-plane) where the scene is symmetric about it. Lengths in m.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ._backend import require_felupe

# Local corner numbering of the faces of quads (edges) and hexahedra (VTK order, as in
# FElupe): used to find the lateral (contact) surface of a mesh.
_QUAD_EDGES = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
_HEX_FACES = np.array(
    [[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
)


def blend_grading(t: np.ndarray, strength: float) -> np.ndarray:
    """Map t in [0, 1] to [0, 1] with spacing refined near t = 0.

    f(t) = (1 - s) t + s t^2: the first spacing is (1 - s) times, the last (1 + s)
    times the uniform one, so the size ratio stays bounded ((1 + s) / (1 - s)) and no
    element degenerates. ``strength`` s must lie in [0, 1).
    """
    if not 0.0 <= strength < 1.0:
        raise ValueError(f"grading strength must lie in [0, 1), got {strength}")
    return (1.0 - strength) * t + strength * t**2


def quarter_disk(radius: float, n: int, top_grading: float = 0.6,
                 surface_grading: float = 0.4) -> Any:
    """Quad mesh of the quarter disk x >= 0, y >= 0 of radius ``radius`` [m].

    FElupe's ``Circle`` (a core square plus two blended blocks, 3 (n - 1)^2 quads, 2 (n - 1)
    edges on the arc) is remapped in polar coordinates: the angle from the top point
    (0, radius), where the contact is, is graded with ``top_grading``; the radius is graded
    toward the surface with ``surface_grading`` (g(s) = s + c s (1 - s)), so that elements
    are finest under the contact. The mapping fixes the symmetry axes and the arc.
    """
    fem = require_felupe()
    if radius <= 0.0:
        raise ValueError(f"radius must be > 0 m, got {radius}")
    if n < 3:
        raise ValueError(f"n (points per edge) must be >= 3, got {n}")
    mesh = fem.Circle(radius=1.0, centerpoint=(0.0, 0.0), n=n, sections=[0])
    x, y = mesh.points[:, 0], mesh.points[:, 1]
    r = np.hypot(x, y)
    phi = (np.pi / 2 - np.arctan2(y, x)) / (np.pi / 2)  # 0 at the top, 1 on the x axis
    phi = np.clip(phi, 0.0, 1.0)
    phi_new = blend_grading(phi, top_grading) * np.pi / 2
    r_new = r + surface_grading * r * (1.0 - r)  # finer near r = 1, fixed at 0 and 1
    points = radius * np.column_stack([r_new * np.sin(phi_new), r_new * np.cos(phi_new)])
    points[np.isclose(x, 0.0, atol=1e-12), 0] = 0.0  # keep symmetry planes exact
    points[np.isclose(y, 0.0, atol=1e-12), 1] = 0.0
    return fem.Mesh(points=points, cells=mesh.cells, cell_type="quad")


def axial_coordinates(length: float, n_cells: int, grading: float = 0.0) -> np.ndarray:
    """Node coordinates z [m] in [0, length], refined toward z = 0 by ``grading``."""
    if length <= 0.0:
        raise ValueError(f"length must be > 0 m, got {length}")
    if n_cells < 1:
        raise ValueError(f"n_cells must be >= 1, got {n_cells}")
    return length * blend_grading(np.linspace(0.0, 1.0, n_cells + 1), grading)


def extrude(section: Any, z: np.ndarray) -> Any:
    """Hexahedral mesh: the quad ``section`` extruded through the coordinates ``z`` [m]."""
    fem = require_felupe()
    z = np.asarray(z, dtype=float)
    points, cells, cell_type = fem.mesh.expand(
        section.points, section.cells, section.cell_type, z=z - z[0]
    )
    points[:, 2] += z[0]
    return fem.Mesh(points=points, cells=cells, cell_type=cell_type)


def lateral_faces(mesh: Any, radius: float, rtol: float = 1e-8) -> np.ndarray:
    """Faces (edges in 2D) of ``mesh`` on the rod's lateral surface r = ``radius``.

    Returns point indices, shape (n_faces, 2) for quads or (n_faces, 4) for hexahedra.
    """
    local = _QUAD_EDGES if mesh.cell_type == "quad" else _HEX_FACES
    r = np.hypot(mesh.points[:, 0], mesh.points[:, 1])
    on = np.isclose(r, radius, rtol=rtol, atol=0.0)
    faces = mesh.cells[:, local].reshape(-1, local.shape[1])
    return faces[np.all(on[faces], axis=1)]


def lumped_face_weights(points: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Integral of each nodal shape function over the faces, per point.

    2D: edge length split half to each end [m]. 3D: bilinear quads integrated with 2x2
    Gauss points [m^2]. ``points`` (npoints, dim) may be deformed coordinates.
    """
    weights = np.zeros(len(points))
    if faces.shape[1] == 2:
        length = np.linalg.norm(points[faces[:, 1]] - points[faces[:, 0]], axis=1)
        np.add.at(weights, faces, 0.5 * length[:, None])
        return weights
    g = 1.0 / np.sqrt(3.0)
    corners = points[faces]  # (nf, 4, 3)
    for xi, eta in [(-g, -g), (g, -g), (g, g), (-g, g)]:
        shape = 0.25 * np.array([(1 - xi) * (1 - eta), (1 + xi) * (1 - eta),
                                 (1 + xi) * (1 + eta), (1 - xi) * (1 + eta)])
        d_xi = 0.25 * np.array([-(1 - eta), (1 - eta), (1 + eta), -(1 + eta)])
        d_eta = 0.25 * np.array([-(1 - xi), -(1 + xi), (1 + xi), (1 - xi)])
        t1 = np.einsum("a,fai->fi", d_xi, corners)
        t2 = np.einsum("a,fai->fi", d_eta, corners)
        jac = np.linalg.norm(np.cross(t1, t2), axis=1)  # Gauss weight 1 per point
        np.add.at(weights, faces, shape[None, :] * jac[:, None])
    return weights


def polygon_area(points_2d: np.ndarray, cells: np.ndarray) -> float:
    """Total area [m^2] of quads ``cells`` with 2D corner coordinates (shoelace)."""
    c = points_2d[cells]  # (n, 4, 2)
    x, y = c[..., 0], c[..., 1]
    return float(0.5 * np.abs(np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y,
                                     axis=1)).sum())
