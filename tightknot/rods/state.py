"""The changing state of a rod model: positions, twist angles, reference frames, velocities.

Only solvers write states. Frames are carried by time-parallel transport from the last
accepted state (Bergou 2010 sec. 4.1), and the reference twist is tracked continuously
(never wrapped), so a closed rod keeps its link.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tightknot.rods import frames
from tightknot.rods.model import Model


@dataclass
class State:
    """State of a :class:`Model`.

    Attributes:
        x: vertex positions [m], shape (vertex_count, 3).
        theta: twist angle of each edge's material frame from its reference frame [rad],
            shape (edge_count,).
        d1_ref: reference director of each edge (unit, normal to the edge), (edge_count, 3).
        t_ref: unit tangent each reference director belongs to, (edge_count, 3).
        m_ref: reference twist of each joint [rad], (joint_count,).
        v: vertex velocities [m/s], (vertex_count, 3).
        theta_dot: twist rates [rad/s], (edge_count,).
        time: simulated time [s] (dynamics only).
        extra: the degrees of freedom an energy term owns beyond the model's (the sectioned
            contact level's section coefficients [m]; :attr:`tightknot.rods.term.
            EnergyTerm.dof_count`), empty without such a term.
    """

    x: np.ndarray
    theta: np.ndarray
    d1_ref: np.ndarray
    t_ref: np.ndarray
    m_ref: np.ndarray
    v: np.ndarray
    theta_dot: np.ndarray
    time: float = 0.0
    extra: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @classmethod
    def initial(cls, model: Model, positions: np.ndarray | None = None) -> State:
        """State at rest velocity with space-parallel reference frames on each rod.

        For a closed rod the closing joint's reference twist is the holonomy of the
        transport around the loop, in (-pi, pi], plus the model's link offset: the
        frame is joined with no excess twist (physics.md sec. 1).
        """
        x = np.array(model.vertex_initial_position if positions is None else positions,
                     dtype=np.float64)
        if x.shape != (model.vertex_count, 3):
            raise ValueError(f"positions must have shape {(model.vertex_count, 3)}, got {x.shape}")
        ev = model.edge_vertex
        e = x[ev[:, 1]] - x[ev[:, 0]]
        t = e / np.linalg.norm(e, axis=1)[:, None]
        d1 = np.empty_like(t)
        for rod in model.rods:
            d1[rod.edge_slice] = frames.space_parallel_frames(t[rod.edge_slice])
        m_ref = frames.reference_twist(d1, t, model.joint_edge) + model.joint_link_offset
        theta = np.zeros(model.edge_count)
        if model.twist:
            for rod in model.rods:
                if rod.closed:
                    # Spread the closing joint's twist evenly (theta_j = j c): an isotropic
                    # rod's equilibrium twist is uniform, m_i = c = sum(m_ref)/N.
                    c = m_ref[rod.joint_slice].sum() / rod.edge_count
                    theta[rod.edge_slice] = c * np.arange(rod.edge_count)
        return cls(
            x=x,
            theta=theta,
            d1_ref=d1,
            t_ref=t,
            m_ref=m_ref,
            v=np.zeros_like(x),
            theta_dot=np.zeros(model.edge_count),
        )

    def copy(self) -> State:
        """A deep copy."""
        return State(
            self.x.copy(), self.theta.copy(), self.d1_ref.copy(), self.t_ref.copy(),
            self.m_ref.copy(), self.v.copy(), self.theta_dot.copy(), self.time,
            self.extra.copy(),
        )

    @property
    def frames(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The accepted frames (t_ref, d1_ref, m_ref) a term with dofs of its own is
        evaluated with (:meth:`tightknot.rods.term.EnergyTerm.evaluate_with_dofs`)."""
        return self.t_ref, self.d1_ref, self.m_ref

    def dofs(self, model: Model) -> np.ndarray:
        """Pack positions and twist angles into the model's dof vector."""
        q = np.empty(model.dof_count)
        q[model.position_dofs] = self.x
        if model.twist:
            q[model.edge_dof] = self.theta
        return q

    def material_frames(self) -> tuple[np.ndarray, np.ndarray]:
        """Material directors (m1, m2) of each edge."""
        return frames.material_frames(self.d1_ref, self.t_ref, self.theta)
