"""Launchers of the elastic kernels: energy split, gradient and Hessian of a model's rods.

Thin functions over :mod:`tightknot.rods.elastic_kernels`; they take host NumPy arrays
(zero-copy on CPU) and the slot maps of a :class:`tightknot.solvers.linear.SparsePattern`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import warp as wp

from tightknot.rods import elastic_kernels as ek
from tightknot.rods.model import Model
from tightknot.warp_setup import init_warp


@dataclass
class ElasticEnergies:
    """Energy split of the elastic rods [J]."""

    stretch: float
    bend: float
    twist: float

    @property
    def total(self) -> float:
        """Sum of the three [J]."""
        return self.stretch + self.bend + self.twist


def _vec3(a: np.ndarray, device: str) -> wp.array:
    return wp.array(np.ascontiguousarray(a, dtype=np.float64), dtype=wp.vec3d, device=device)


def _f64(a: np.ndarray, device: str) -> wp.array:
    return wp.array(np.ascontiguousarray(a, dtype=np.float64), dtype=wp.float64, device=device)


class ElasticForces:
    """Evaluates the stretch, bend and twist energies of a model (Warp kernels).

    Args:
        model: the rod model.
        joint_slot, edge_slot: Hessian slot maps (from a SparsePattern); None: no Hessian.
    """

    def __init__(
        self, model: Model, joint_slot: np.ndarray | None = None,
        edge_slot: np.ndarray | None = None,
    ) -> None:
        init_warp()
        self.model = model
        dev = model.device
        self.device = dev
        self._e_stretch = wp.zeros(model.edge_count, dtype=wp.float64, device=dev)
        self._e_bend = wp.zeros(model.joint_count, dtype=wp.float64, device=dev)
        self._e_twist = wp.zeros(model.joint_count, dtype=wp.float64, device=dev)
        self._grad = wp.zeros(model.dof_count, dtype=wp.float64, device=dev)
        self._empty_slots = wp.zeros((1, 1), dtype=wp.int32, device=dev)
        self._empty_f = wp.zeros(1, dtype=wp.float64, device=dev)
        self.set_slots(joint_slot, edge_slot)

    def set_slots(self, joint_slot: np.ndarray | None, edge_slot: np.ndarray | None) -> None:
        """Install the Hessian slot maps of a new pattern."""
        dev = self.device
        if joint_slot is None or edge_slot is None:
            self._jslot = self._eslot = None
            return
        self._jslot = wp.array(joint_slot, dtype=wp.int32, device=dev)
        self._eslot = wp.array(edge_slot, dtype=wp.int32, device=dev)

    def evaluate(
        self,
        x: np.ndarray,
        theta: np.ndarray,
        m_ref: np.ndarray,
        edge_rest_length: np.ndarray,
        want_grad: bool = True,
        hess_data: wp.array | None = None,
    ) -> tuple[ElasticEnergies, np.ndarray | None]:
        """Energies, and the gradient over all dofs [N or N m] when ``want_grad``.

        When ``hess_data`` (a zeroed Warp float64 array of the pattern's nnz) is given, the
        Hessian entries are added into it.
        """
        m = self.model
        dev = self.device
        wx = _vec3(x, dev)
        wth = _f64(theta, dev) if m.twist else self._empty_f
        wmr = _f64(m_ref, dev)
        wrest = _f64(edge_rest_length, dev)
        want_hess = hess_data is not None
        if want_hess and self._jslot is None:
            raise RuntimeError("ElasticForces has no Hessian slot map (call set_slots)")
        if want_grad or want_hess:
            self._grad.zero_()
        hout = hess_data if want_hess else self._empty_f
        jslot = self._jslot if want_hess else self._empty_slots
        eslot = self._eslot if want_hess else self._empty_slots
        wg, wh = int(want_grad or want_hess), int(want_hess)
        if m.edge_count:
            wp.launch(
                ek.stretch_kernel, dim=m.edge_count, device=dev,
                inputs=[m.wp("edge_vertex"), m.wp("edge_mu_area"), m.wp("edge_dofs"),
                        wx, wrest, eslot, wg, wh],
                outputs=[self._e_stretch, self._grad, hout],
            )
        if m.joint_count:
            wp.launch(
                ek.bend_twist_kernel, dim=m.joint_count, device=dev,
                inputs=[m.wp("joint_vertex"), m.wp("joint_edge"), m.wp("joint_bend_stiffness"),
                        m.wp("joint_twist_stiffness"), m.wp("joint_thinning_exponent"),
                        m.wp("joint_dofs"), int(m.twist), wx, wth, wmr, wrest, jslot, wg, wh],
                outputs=[self._e_bend, self._e_twist, self._grad, hout],
            )
        energies = ElasticEnergies(
            stretch=float(self._e_stretch.numpy().sum()) if m.edge_count else 0.0,
            bend=float(self._e_bend.numpy().sum()) if m.joint_count else 0.0,
            twist=float(self._e_twist.numpy().sum()) if m.joint_count else 0.0,
        )
        grad = self._grad.numpy().copy() if want_grad else None
        return energies, grad

    def transport_frames(
        self, x: np.ndarray, d1_base: np.ndarray, t_base: np.ndarray, m_ref_base: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Reference frames and reference twist at positions ``x``, carried by time-parallel
        transport from the base frames (Bergou 2010 sec. 4.1). Returns (d1, t, m_ref)."""
        m = self.model
        dev = self.device
        d1 = wp.empty(m.edge_count, dtype=wp.vec3d, device=dev)
        t = wp.empty(m.edge_count, dtype=wp.vec3d, device=dev)
        mref = wp.empty(max(m.joint_count, 1), dtype=wp.float64, device=dev)
        wp.launch(ek.transport_frames_kernel, dim=m.edge_count, device=dev,
                  inputs=[m.wp("edge_vertex"), _vec3(x, dev), _vec3(d1_base, dev),
                          _vec3(t_base, dev)], outputs=[d1, t])
        if m.joint_count:
            wp.launch(ek.reference_twist_kernel, dim=m.joint_count, device=dev,
                      inputs=[m.wp("joint_edge"), d1, t, _f64(m_ref_base, dev)], outputs=[mref])
        return d1.numpy(), t.numpy(), mref.numpy()[: m.joint_count]
