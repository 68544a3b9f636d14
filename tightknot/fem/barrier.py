"""Barrier contact between deformable FEM bodies, through the IPC Toolkit (ipctk).

The contact surfaces (triangles in 3D, edges in plane strain) of one FElupe mesh carry
the Incremental Potential Contact barrier of Li et al. (ACM TOG 39, 2020, eq. 6) with
area weighting (the "convergent" IPC of Li, Kaufman & Jiang, 2023), so that the barrier
is a surface integral and its pressure is independent of the mesh:

    U(x) = D0^dim P(x / D0),   P(X) = kappa sum_c w_c b(d_c^2, dhat^2) / dhat^3,

with b(s, s_hat) = -(s - s_hat)^2 ln(s / s_hat) the clamped log barrier on squared
distances and w_c the collision's area weight (ipctk's ``BarrierPotential`` with
``use_physical_barrier``; the collision set is the "improved max approximation" of Li et
al. 2023, whose weights sum to the facing area also where nodes face nodes). Far inside
the activation distance (d << dhat) the contact pressure is
p = -dU/dd / area = 2 kappa dhat / d (checked in tests/fem/test_barrier.py),
so ``kappa`` [Pa] is a pressure scale: at p = 0.5 E and kappa = 0.01 E the gap is
d = 0.04 dhat.

All of ipctk's geometry runs in D0-scaled coordinates X = x / D0: its CCD tolerance and
its distance tests are absolute, and O(1) coordinates keep them meaningful. Energies,
gradients and Hessians are returned in SI units (J, N, N/m; per unit depth in plane
strain).

The object is also a FElupe item (``.field``, ``.results``, ``.assemble.vector``,
``.assemble.matrix``), so it can sit beside a solid body in FElupe's own tools.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

import numpy as np
import scipy.sparse as sp

from ._backend import require_ipctk

DHAT_OVER_D0: float = 3e-4
"""Barrier activation distance dhat [D0]: a larger one biases the force high (the gap
that carries the pressure shortens the bodies' approach; a prototype measured +2.5 % at
1e-3 D0 on the two-rod squeeze)."""

KAPPA_OVER_E: float = 0.01
"""Barrier pressure scale kappa [E]: the gap at p = 0.5 E is 0.04 dhat (see above)."""


def quads_to_triangles(quads: np.ndarray) -> np.ndarray:
    """Split each quad (corners a, b, c, d) into the triangles (a, b, c) and (a, c, d)."""
    quads = np.asarray(quads)
    return np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]).astype(np.int32)


@dataclass
class BarrierContact:
    """IPC barrier on the surface ``faces`` of the mesh of the FElupe field container
    ``field`` (displacement first).

    ``faces`` index the mesh points: triangles (n, 3) in 3D, edges (n, 2) in 2D.
    ``length_scale`` D0 [m] scales the coordinates given to ipctk; ``dhat_over_scale`` the
    activation distance over D0; ``stiffness`` kappa [Pa]. The collision set is rebuilt
    at every evaluation (the surfaces slide and the patch grows).
    """

    field: Any
    faces: np.ndarray
    length_scale: float
    stiffness: float
    dhat_over_scale: float = DHAT_OVER_D0
    results: Any = field(init=False)
    assemble: Any = field(init=False)

    def __post_init__(self) -> None:
        ipctk = require_ipctk()
        self._ipctk = ipctk
        mesh = self.field.region.mesh
        self.dim = int(self.field[0].values.shape[1])
        rest = np.asfortranarray(mesh.points[:, : self.dim] / self.length_scale)
        faces = np.asarray(self.faces, dtype=np.int32)
        if self.dim == 3:
            if faces.shape[1] != 3:
                raise ValueError("3D barrier surfaces must be triangles (n, 3)")
            edges = ipctk.edges(faces)
            self.cmesh = ipctk.CollisionMesh.build_from_full_mesh(rest, edges, faces)
        else:
            if faces.shape[1] != 2:
                raise ValueError("2D barrier surfaces must be edges (n, 2)")
            self.cmesh = ipctk.CollisionMesh.build_from_full_mesh(rest, faces)
        self.potential = ipctk.BarrierPotential(self.dhat_over_scale, self.stiffness, True)
        self.ccd = ipctk.TightInclusionCCD()
        self.results = SimpleNamespace(force=None, stiffness=None)
        self.assemble = SimpleNamespace(vector=self._vector, matrix=self._matrix)
        # SI factors: U = D0^dim P, grad U = D0^(dim-1) grad_X P, hess U = D0^(dim-2) ...
        self._energy_factor = self.length_scale**self.dim

    def _vertices(self, displacement: np.ndarray | None = None) -> np.ndarray:
        """Collision-mesh vertices [D0] of the current (or the given) displacement [m]."""
        u = self.field[0].values if displacement is None else displacement
        full = self.field.region.mesh.points[:, : self.dim] + u
        return np.asfortranarray(self.cmesh.vertices(np.asfortranarray(full / self.length_scale)))

    def _collisions(self, v: np.ndarray, within: float | None = None) -> Any:
        c = self._ipctk.NormalCollisions()
        c.use_area_weighting = True
        # the original IPC set counts a vertex facing a vertex once per adjacent edge
        # pair: 1.75 times the area of two aligned chains of four edges (the mirrored
        # meshes of the nip scenes); the improved max approximation counts it once
        c.collision_set_type = self._ipctk.NormalCollisions.CollisionSetType.IMPROVED_MAX_APPROX
        c.build(self.cmesh, v, self.dhat_over_scale if within is None else within)
        return c

    def minimum_distance_over_scale(self, displacement: np.ndarray | None = None,
                                    within: float | None = None) -> float:
        """Smallest distance [D0] between non-adjacent surface elements closer than
        ``within`` [D0] (default dhat); inf when none is, 0 where surfaces cross."""
        v = self._vertices(displacement)
        c = self._collisions(v, within)
        if c.empty():
            return float("inf")
        return float(np.sqrt(c.compute_minimum_distance(self.cmesh, v)))  # ipctk: squared

    def energy(self, displacement: np.ndarray | None = None) -> float:
        """Barrier energy U [J] (3D) or [J/m] (plane strain); inf if surfaces cross."""
        v = self._vertices(displacement)
        c = self._collisions(v)
        if c.empty():
            return 0.0
        if c.compute_minimum_distance(self.cmesh, v) <= 0.0:
            return float("inf")
        return self._energy_factor * float(self.potential(c, self.cmesh, v))

    def gradient(self, displacement: np.ndarray | None = None) -> np.ndarray:
        """dU/du over all dofs of the field (point-major), [N] or [N/m]."""
        v = self._vertices(displacement)
        c = self._collisions(v)
        n = self.field[0].values.size
        if c.empty():
            return np.zeros(n)
        g = self.cmesh.to_full_dof(self.potential.gradient(c, self.cmesh, v))
        return np.asarray(g).ravel() * self._energy_factor / self.length_scale

    def hessian(self, displacement: np.ndarray | None = None, project: bool = True
                ) -> sp.csr_matrix:
        """d2U/du2 [N/m] over all dofs; ``project``: each collision's block projected to
        positive semi-definite (clamped eigenvalues), as IPC does far from a solution."""
        v = self._vertices(displacement)
        c = self._collisions(v)
        n = self.field[0].values.size
        if c.empty():
            return sp.csr_matrix((n, n))
        method = (self._ipctk.PSDProjectionMethod.CLAMP if project
                  else self._ipctk.PSDProjectionMethod.NONE)
        h = self.cmesh.to_full_dof(self.potential.hessian(c, self.cmesh, v, method))
        return sp.csr_matrix(h) * (self._energy_factor / self.length_scale**2)

    def nodal_forces(self, displacement: np.ndarray | None = None) -> np.ndarray:
        """Contact forces on the mesh points, -dU/du, shape (npoints, dim) [N or N/m]."""
        return -self.gradient(displacement).reshape(-1, self.dim)

    def max_step(self, displacement: np.ndarray, step: np.ndarray) -> float:
        """Largest fraction in [0, 1] of ``step`` [m] from ``displacement`` [m] that keeps
        the surfaces apart (Tight Inclusion CCD, conservative rescaling 0.8)."""
        v0 = self._vertices(displacement)
        v1 = self._vertices(displacement + step)
        return float(self._ipctk.compute_collision_free_stepsize(
            self.cmesh, v0, v1, narrow_phase_ccd=self.ccd))

    # FElupe item interface: the residual is +dU/du, the matrix d2U/du2 (projected)
    def _vector(self, field: Any = None, **_: Any) -> sp.csr_matrix:
        self.results.force = sp.csr_matrix(self.gradient().reshape(-1, 1))
        return self.results.force

    def _matrix(self, field: Any = None, **_: Any) -> sp.csr_matrix:
        self.results.stiffness = self.hessian(project=True)
        return self.results.stiffness
