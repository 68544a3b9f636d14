"""Shared pieces of the two-deformable-body scenes: one mesh of two bodies, barrier
contact between their lateral patches, and measurements of the contact on one body."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._backend import require_felupe
from ..barrier import DHAT_OVER_D0, KAPPA_OVER_E, BarrierContact, quads_to_triangles
from ..material import BULK_MODULUS, SHEAR_MODULUS, nearly_incompressible_solid
from ..mesh import lumped_face_weights

GAP_OVER_DHAT: float = 1.0
"""Initial gap between the bodies [dhat]: apart (the barrier needs a positive distance)
and just outside its activation distance, so the unloaded state carries no force."""


def stack(meshes: list[Any]) -> tuple[Any, list[np.ndarray]]:
    """One FElupe mesh of several meshes of the same cell type; returns it and each
    mesh's point indices in it."""
    fem = require_felupe()
    points, cells, index, offset = [], [], [], 0
    for m in meshes:
        points.append(m.points)
        cells.append(m.cells + offset)
        index.append(np.arange(offset, offset + m.npoints))
        offset += m.npoints
    mesh = fem.Mesh(points=np.vstack(points), cells=np.vstack(cells),
                    cell_type=meshes[0].cell_type)
    return mesh, index


def bodies_solid(meshes: list[Any], youngs_modulus: float
                 ) -> tuple[Any, list[np.ndarray], Any, Any]:
    """The bodies ``meshes`` (hexahedra) as one mesh (:func:`stack`), its 3D displacement
    field and the nearly incompressible solid of Young's modulus ``youngs_modulus`` [Pa]
    (mu = E/3, K/mu the material's ratio); returns (mesh, point indices per body, field,
    solid)."""
    fem = require_felupe()
    body, index = stack(meshes)
    field = fem.FieldContainer([fem.Field(fem.RegionHexahedron(body), dim=3)])
    mu = youngs_modulus / 3.0
    solid = nearly_incompressible_solid(field, mu=mu, bulk=BULK_MODULUS * mu / SHEAR_MODULUS)
    return body, index, field, solid


def turned_about_x_eq_z(mesh: Any, y_mid2: float) -> Any:
    """``mesh`` (hexahedra) turned by 180 degrees about the line x = z, y = y_mid2 / 2:
    (x, y, z) -> (z, y_mid2 - y, x), a proper rotation, so the cells keep their
    orientation (a rod along e_z becomes a rod along e_x facing it)."""
    fem = require_felupe()
    p = mesh.points
    return fem.Mesh(points=np.column_stack([p[:, 2], y_mid2 - p[:, 1], p[:, 0]]),
                    cells=mesh.cells, cell_type="hexahedron")


def barrier_faces(faces: np.ndarray) -> np.ndarray:
    """The barrier's surface elements of lateral ``faces``: edges in 2D as they are,
    quads in 3D split into triangles."""
    return faces.astype(np.int32) if faces.shape[1] == 2 else quads_to_triangles(faces)


def make_barrier(field: Any, faces: np.ndarray, diameter: float, youngs_modulus: float,
                 dhat_over_d0: float = DHAT_OVER_D0) -> BarrierContact:
    """Barrier contact on the lateral ``faces`` (both bodies), kappa = 0.01 E, in D0 units."""
    return BarrierContact(field, barrier_faces(faces), length_scale=diameter,
                          stiffness=KAPPA_OVER_E * youngs_modulus,
                          dhat_over_scale=dhat_over_d0)


def nodal_contact(contact: BarrierContact, x: np.ndarray, faces: np.ndarray,
                  nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Contact forces on ``nodes`` (m, dim) [N or N/m] and their true pressures (m,) [Pa]:
    force magnitude over the node's deformed surface weight on ``faces``."""
    force = contact.nodal_forces()[nodes]
    weight = lumped_face_weights(x, faces)[nodes]
    magnitude = np.linalg.norm(force, axis=1)
    pressure = np.divide(magnitude, weight, out=np.zeros_like(magnitude), where=weight > 0)
    return force, pressure


LOADED_FRACTION: float = 0.01
"""A node counts as in contact where its pressure exceeds this fraction of the peak: the
barrier also pushes, weakly, on nodes a gap just below dhat away (a node one element past
a Hertz edge has a gap of 1e-3 D0, beyond dhat = 3e-4 D0, while the last node inside
carries 0.3 or more of the peak), and those must not move the measured edge."""


def contact_edge(s: np.ndarray, p: np.ndarray) -> float:
    """Edge [m] of the contact along the ascending positions ``s`` from its centre, from
    the pressures ``p`` (:func:`tightknot.fem.measure.edge_position` on the loaded nodes)."""
    from ..measure import edge_position

    if p.size == 0 or p.max() <= 0.0:
        return 0.0
    return edge_position(s, np.where(p > LOADED_FRACTION * p.max(), p, 0.0))
