"""Launchers of the elastic kernels: energy split, gradient and Hessian of a model's rods.

Thin functions over :mod:`tightknot.rods.elastic_kernels`; they take host NumPy arrays
(copied into reused device arrays, :mod:`tightknot.rods.staging`) and the slot maps of a
:class:`tightknot.solvers.linear.SparsePattern`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import warp as wp

from tightknot.rods import elastic_kernels as ek
from tightknot.rods.model import Model
from tightknot.rods.staging import Launches, Staging
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
        # Inputs and outputs reused from call to call, and the launches recorded over
        # them (tightknot.rods.staging: the per-call array creation and argument packing
        # were a fifth of a small rod's Newton iteration).
        self._in_x = Staging(wp.vec3d, dev)
        self._in_theta = Staging(wp.float64, dev)
        self._in_mref = Staging(wp.float64, dev)
        self._in_rest = Staging(wp.float64, dev)
        self._in_d1 = Staging(wp.vec3d, dev)
        self._in_t = Staging(wp.vec3d, dev)
        self._in_mref_base = Staging(wp.float64, dev)
        self._d1 = wp.empty(model.edge_count, dtype=wp.vec3d, device=dev)
        self._t = wp.empty(model.edge_count, dtype=wp.vec3d, device=dev)
        self._mref = wp.empty(max(model.joint_count, 1), dtype=wp.float64, device=dev)
        self._launches = Launches()
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
        wx = self._in_x.put(x)
        wth = self._in_theta.put(theta) if m.twist else self._empty_f
        wmr = self._in_mref.put(m_ref)
        wrest = self._in_rest.put(edge_rest_length)
        want_hess = hess_data is not None
        if want_hess and self._jslot is None:
            raise RuntimeError("ElasticForces has no Hessian slot map (call set_slots)")
        if want_grad or want_hess:
            self._grad.zero_()
        hout = hess_data if want_hess else self._empty_f
        jslot = self._jslot if want_hess else self._empty_slots
        eslot = self._eslot if want_hess else self._empty_slots
        wg, wh = int(want_grad or want_hess), int(want_hess)
        launch = self._launches.launch
        if m.edge_count:
            launch(
                ek.stretch_kernel, m.edge_count, dev,
                [m.wp("edge_vertex"), m.wp("edge_mu_area"), m.wp("edge_dofs"),
                 wx, wrest, eslot, wg, wh],
                [self._e_stretch, self._grad, hout], variant=(wg, wh),
            )
        if m.joint_count:
            launch(
                ek.bend_twist_kernel, m.joint_count, dev,
                [m.wp("joint_vertex"), m.wp("joint_edge"), m.wp("joint_bend_stiffness"),
                 m.wp("joint_twist_stiffness"), m.wp("joint_thinning_exponent"),
                 m.wp("joint_dofs"), int(m.twist), wx, wth, wmr, wrest, jslot, wg, wh],
                [self._e_bend, self._e_twist, self._grad, hout], variant=(wg, wh),
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
        d1, t, mref = self._d1, self._t, self._mref
        self._launches.launch(ek.transport_frames_kernel, m.edge_count, dev,
                              [m.wp("edge_vertex"), self._in_x.put(x), self._in_d1.put(d1_base),
                               self._in_t.put(t_base)], [d1, t])
        if m.joint_count:
            self._launches.launch(ek.reference_twist_kernel, m.joint_count, dev,
                                  [m.wp("joint_edge"), d1, t, self._in_mref_base.put(m_ref_base)],
                                  [mref])
        # Copies: the arrays are overwritten by the next call, the results are kept.
        return d1.numpy().copy(), t.numpy().copy(), mref.numpy()[: m.joint_count].copy()
