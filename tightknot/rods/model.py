"""The static rod model: topology, rest geometry, stiffness, mass and the degree-of-freedom map.

Only :class:`tightknot.rods.builder.RodBuilder` makes a model. Arrays are structure of
arrays, SI units, entity first (``edge_rest_length``, ``joint_vertex``...), held on the
host as NumPy arrays and mirrored on the Warp ``device`` for the kernels.

Degrees of freedom (Bergou et al. 2010, sec. 4): per vertex its position (3), per edge
its twist angle theta (1) when the model has twist. They are interleaved per rod,
``[x0 y0 z0 theta0 x1 y1 z1 theta1 ...]``, so an open rod's Hessian is banded.

A *joint* is the bend/twist stencil at a vertex with two edges (every interior vertex
of an open rod, every vertex of a closed rod): vertices (i-1, i, i+1), edges (i-1, i).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import warp as wp

from tightknot.rods.material import Material
from tightknot.warp_setup import init_warp


@dataclass(frozen=True)
class RodInfo:
    """One rod of a model.

    Attributes:
        vertex_start: index of its first vertex in the model's vertex arrays.
        vertex_count: number of vertices.
        edge_start: index of its first edge.
        edge_count: number of edges (vertex_count - 1 open, vertex_count closed).
        joint_start: index of its first joint.
        joint_count: number of joints.
        closed: True for a closed (periodic) rod.
        diameter: rest diameter D0 [m].
        material: its material.
    """

    vertex_start: int
    vertex_count: int
    edge_start: int
    edge_count: int
    joint_start: int
    joint_count: int
    closed: bool
    diameter: float
    material: Material

    @property
    def vertex_slice(self) -> slice:
        """Slice of this rod's vertices in model arrays."""
        return slice(self.vertex_start, self.vertex_start + self.vertex_count)

    @property
    def edge_slice(self) -> slice:
        """Slice of this rod's edges in model arrays."""
        return slice(self.edge_start, self.edge_start + self.edge_count)

    @property
    def joint_slice(self) -> slice:
        """Slice of this rod's joints in model arrays."""
        return slice(self.joint_start, self.joint_start + self.joint_count)


@dataclass
class Model:
    """Static description of one or more discrete elastic rods.

    Attributes (host NumPy arrays; ``wp_*`` mirrors live on ``device``):
        rods: per-rod information.
        twist: whether edges carry twist degrees of freedom.
        vertex_dof: first dof index of each vertex, shape (vertex_count,), int32.
        edge_dof: twist dof of each edge (-1 without twist), shape (edge_count,), int32.
        dof_count: total number of degrees of freedom.
        edge_vertex: vertices of each edge, shape (edge_count, 2), int32.
        edge_rest_length: rest length of each edge [m], shape (edge_count,).
        edge_mu_area: mu A0 of each edge [N] (neo-Hookean stretch stiffness).
        edge_radius: rest radius of each edge [m].
        edge_rot_inertia: rho J0 l_bar, rotational inertia of each edge's twist [kg m^2].
        edge_rod: rod index of each edge.
        joint_vertex: (i-1, i, i+1) of each joint, shape (joint_count, 3), int32.
        joint_edge: (edge before, edge after) of each joint, shape (joint_count, 2), int32.
        joint_bend_stiffness: E I0 at each joint [N m^2].
        joint_twist_stiffness: G J0 at each joint [N m^2].
        joint_thinning_exponent: q = 4 nu + 1 at each joint [-].
        vertex_mass: lumped mass of each vertex [kg].
        vertex_rod: rod index of each vertex.
        joint_dofs: the 11 dofs of each joint stencil (x_{i-1}, x_i, x_{i+1}, theta_before,
            theta_after), shape (joint_count, 11), -1 where absent.
        edge_dofs: the 6 position dofs of each edge, shape (edge_count, 6).
        vertex_initial_position: positions given to the builder [m], shape (vertex_count, 3).
        joint_link_offset: extra reference twist 2 pi k [rad] at the closing joint of a
            closed rod given ``link_offset=k`` turns of excess link (0 elsewhere).
        device: Warp device of the mirrored arrays.
        mirror_rod_pairs: pairs of rods (a < b) that stand for one body's mirror images in
            a symmetric scene (a stack that the FEM holds on a symmetry plane,
            :func:`tightknot.fem.rod_model.wrap_scene`): they are not material to each
            other, so they are neither contact candidates nor checked for proximity.
            Empty for every knot.
    """

    rods: list[RodInfo]
    twist: bool
    vertex_dof: np.ndarray
    edge_dof: np.ndarray
    dof_count: int
    edge_vertex: np.ndarray
    edge_rest_length: np.ndarray
    edge_mu_area: np.ndarray
    edge_radius: np.ndarray
    edge_rot_inertia: np.ndarray
    edge_rod: np.ndarray
    joint_vertex: np.ndarray
    joint_edge: np.ndarray
    joint_bend_stiffness: np.ndarray
    joint_twist_stiffness: np.ndarray
    joint_thinning_exponent: np.ndarray
    vertex_mass: np.ndarray
    vertex_rod: np.ndarray
    joint_dofs: np.ndarray
    edge_dofs: np.ndarray
    vertex_initial_position: np.ndarray
    joint_link_offset: np.ndarray
    device: str = "cpu"
    mirror_rod_pairs: tuple[tuple[int, int], ...] = ()
    wp_arrays: dict[str, wp.array] = field(default_factory=dict, repr=False)

    @property
    def vertex_count(self) -> int:
        """Number of vertices of all rods."""
        return int(self.vertex_dof.shape[0])

    @property
    def edge_count(self) -> int:
        """Number of edges of all rods."""
        return int(self.edge_vertex.shape[0])

    @property
    def joint_count(self) -> int:
        """Number of bend/twist joints of all rods."""
        return int(self.joint_vertex.shape[0])

    @property
    def position_dofs(self) -> np.ndarray:
        """Dof indices of all vertex positions, shape (vertex_count, 3) (read-only)."""
        # Built once: the solvers index with it several times per Newton iteration
        # (65 000 rebuilds, 0.39 s, in a 32-rod batch). Keyed on the dof map's identity
        # and shape, so a model whose vertex_dof is replaced gets a fresh table.
        key = (id(self.vertex_dof), self.vertex_dof.shape)
        cached = self.__dict__.get("_position_dofs")
        if cached is None or cached[0] != key:
            table = self.vertex_dof[:, None] + np.arange(3, dtype=np.int64)[None, :]
            table.setflags(write=False)
            cached = (key, table)
            self.__dict__["_position_dofs"] = cached
        return cached[1]

    def mirror_matrix(self) -> np.ndarray:
        """Whether rods a and b are mirror images (:attr:`mirror_rod_pairs`), (rod count,
        rod count) bool, symmetric."""
        out = np.zeros((len(self.rods), len(self.rods)), dtype=np.bool_)
        for a, b in self.mirror_rod_pairs:
            out[a, b] = out[b, a] = True
        return out

    def wp(self, name: str) -> wp.array:
        """The Warp mirror of host array ``name`` on the model's device."""
        return self.wp_arrays[name]

    def upload(self) -> None:
        """(Re)create the Warp mirrors of the arrays the kernels read."""
        init_warp()
        dev = self.device
        f64 = wp.float64
        self.wp_arrays = {
            "edge_vertex": wp.array(self.edge_vertex, dtype=wp.vec2i, device=dev),
            "edge_mu_area": wp.array(self.edge_mu_area, dtype=f64, device=dev),
            "joint_vertex": wp.array(self.joint_vertex, dtype=wp.vec3i, device=dev),
            "joint_edge": wp.array(self.joint_edge, dtype=wp.vec2i, device=dev),
            "joint_bend_stiffness": wp.array(self.joint_bend_stiffness, dtype=f64, device=dev),
            "joint_twist_stiffness": wp.array(self.joint_twist_stiffness, dtype=f64, device=dev),
            "joint_thinning_exponent": wp.array(
                self.joint_thinning_exponent, dtype=f64, device=dev
            ),
            "joint_dofs": wp.array(self.joint_dofs, dtype=wp.int32, device=dev),
            "edge_dofs": wp.array(self.edge_dofs, dtype=wp.int32, device=dev),
        }

    def rod_length(self, positions: np.ndarray, rod: int = 0) -> float:
        """Current centerline length of rod ``rod`` [m] for vertex ``positions`` (N, 3)."""
        e = self.edge_vertex[self.rods[rod].edge_slice]
        return float(np.linalg.norm(positions[e[:, 1]] - positions[e[:, 0]], axis=1).sum())

    def rest_length(self, rod: int = 0) -> float:
        """Rest length L0 of rod ``rod`` [m]."""
        return float(self.edge_rest_length[self.rods[rod].edge_slice].sum())

    def vertex_max_of_edges(self, values: np.ndarray) -> np.ndarray:
        """Per vertex, the largest of its edges' ``values`` (non-negative; 0 for a vertex
        without edges)."""
        ev = self.edge_vertex
        out = np.zeros(self.vertex_count)
        np.maximum.at(out, ev[:, 0], values)
        np.maximum.at(out, ev[:, 1], values)
        return out

    def vertex_mean_of_edges(self, values: np.ndarray) -> np.ndarray:
        """Per vertex, the mean of its edges' ``values`` (0 for a vertex without edges)."""
        ev = self.edge_vertex
        total = np.zeros(self.vertex_count)
        count = np.zeros(self.vertex_count)
        np.add.at(total, ev[:, 0], values)
        np.add.at(total, ev[:, 1], values)
        np.add.at(count, ev[:, 0], 1.0)
        np.add.at(count, ev[:, 1], 1.0)
        return total / np.maximum(count, 1.0)
