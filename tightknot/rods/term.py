"""The interface of an energy term added to the elastic rods (the contact layer, an obstacle).

A :class:`tightknot.solvers.system.RodSystem` owns the model's elastic energy and its sparse
Hessian pattern; extra terms add their energy, gradient and Hessian through the methods
below, which are all the system calls. A term either returns its Hessian as COO triplets
(:meth:`EnergyTerm.evaluate`) or, with ``assembles_in_place``, adds it straight into the
system's CSC data through the block tables of the system's pattern
(:meth:`EnergyTerm.evaluate_into`); then the system asks which blocks were missing and grows
its pattern, and between load steps asks which blocks still interact and compacts it.

A term may own degrees of freedom beyond the model's (``dof_count`` > 0: the sectioned contact
level's section coefficients). The state keeps their values (``State.extra``), the system
appends them to its free dofs, and the term is evaluated by :meth:`EnergyTerm.
evaluate_with_dofs`, with the state's accepted frames.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
import warp as wp

#: COO triplets (rows, cols, values) over global dofs.
Coo = tuple[np.ndarray, np.ndarray, np.ndarray]


@dataclass
class BlockHessian:
    """A term's Hessian as dense blocks between nodes (a node: a vertex with its b dofs,
    e.g. its 3 coordinates and its section coefficients).

    Attributes:
        node_dofs: the extended dofs of each node (model dofs, then ``model.dof_count + j``
            for a term's own dof j; -1 where a node has none), (nodes, b) int64.
        keys: the node pairs (row node, column node) of the blocks, (U, 2) int64, unique.
        blocks: the blocks, (U, b, b) [J per unit of the two dofs].
        full_rows, full_cols: whether each block's rows (columns) past a node's first 3
            dofs (its position) may be nonzero, (U,) bool; None: all may. A block that
            couples positions only then adds no structural zeros to the matrix.
        low_rank: a dense update U C U^T of the Hessian beside the blocks, U over the
            extended dofs (model dofs, then the term's), (model.dof_count + dof_count, m),
            and C (m, m); None: none.
    """

    node_dofs: np.ndarray
    keys: np.ndarray
    blocks: np.ndarray
    full_rows: np.ndarray | None = None
    full_cols: np.ndarray | None = None
    low_rank: tuple[np.ndarray, np.ndarray] | None = None

    def masks(self) -> tuple[np.ndarray, np.ndarray]:
        """``full_rows`` and ``full_cols``, all True where not given."""
        every = np.ones(self.keys.shape[0], dtype=bool)
        return (every if self.full_rows is None else self.full_rows,
                every if self.full_cols is None else self.full_cols)


class EnergyTerm(Protocol):
    """An energy term over a model's vertex positions. Subclass it to get the defaults
    (no in-place assembly, no blocks, no step bound, no state check)."""

    #: Name of the term in the system's energy split.
    name: str = "term"
    #: The term adds its Hessian into the system's CSC data (:meth:`evaluate_into`).
    assembles_in_place: bool = False
    #: The term keeps pieces of rod from passing through each other (a contact layer):
    #: the system then checks every accepted state independently
    #: (:class:`tightknot.rods.proximity.ProximityCheck`).
    keeps_apart: bool = False
    #: Degrees of freedom the term owns beyond the model's, kept in ``State.extra`` and
    #: appended to the system's free dofs (0: none).
    dof_count: int = 0

    def initial_dofs(self) -> np.ndarray:
        """The values of the term's own dofs in a new state (length ``dof_count``)."""
        return np.zeros(self.dof_count)

    def evaluate_with_dofs(self, x: np.ndarray, extra: np.ndarray,
                           frames: tuple[np.ndarray, np.ndarray, np.ndarray],
                           rest: np.ndarray, want_grad: bool, want_hess: bool,
                           twist: np.ndarray | None = None
                           ) -> tuple[float, np.ndarray | None, np.ndarray | None,
                                      BlockHessian | None]:
        """For a term with dofs of its own: the energy [J] at positions ``x`` [m] (V, 3),
        its own dofs ``extra`` and edge rest lengths ``rest`` [m], with the state's accepted
        frames ``frames`` = (t_ref, d1_ref, m_ref) (unit tangents and reference directors
        per edge, reference twist per joint [rad]); its gradient over the positions (V, 3)
        [N] and over its dofs (dof_count,), and its Hessian in node blocks over the extended
        dofs (:class:`BlockHessian`; None where not asked). ``twist``: the reference twist
        per joint [rad] of the frames carried to ``x`` (None: the accepted ``m_ref``)."""
        raise NotImplementedError(f"{type(self).__name__} owns no dofs")

    def begin_load_step(self, x: np.ndarray, rest: np.ndarray) -> None:
        """The system moved to a new load step: positions ``x`` [m] and edge rest lengths
        ``rest`` [m] at its start (a term may adapt to the deformed rod once per step)."""
        return None

    def evaluate(self, x: np.ndarray, rest: np.ndarray, want_grad: bool,
                 want_hess: bool) -> tuple[float, np.ndarray | None, Coo | None]:
        """Energy [J] at positions ``x`` [m] (vertex_count, 3) and edge rest lengths
        ``rest`` [m], its gradient over the positions (vertex_count, 3) [N] (None unless
        asked) and its Hessian as COO triplets over global dofs (None unless asked)."""
        ...

    def evaluate_into(self, x: np.ndarray, rest: np.ndarray, tables: tuple[wp.array, ...],
                      data: wp.array) -> tuple:
        """Energy [J] and gradient (vertex_count, 3) [N], the Hessian added into ``data``
        (CSC data, zeroed by the caller) through the block ``tables`` of the system's
        pattern. The gradient is None when a block was missing from the tables (the
        caller grows its pattern by :meth:`missing_blocks` and evaluates again); a third
        item may hold Hessian terms outside the pair blocks (COO over global dofs)."""
        raise NotImplementedError(f"{type(self).__name__} does not assemble in place")

    def missing_blocks(self) -> np.ndarray:
        """Vertex-block keys ``vr * V + vc`` the last :meth:`evaluate_into` needed."""
        return np.zeros(0, dtype=np.int64)

    def active_blocks(self) -> np.ndarray:
        """Vertex-block keys of what interacted at the last evaluation (kept when the
        system compacts its pattern between load steps)."""
        return np.zeros(0, dtype=np.int64)

    def max_step(self, x: np.ndarray, dx: np.ndarray, rest: np.ndarray) -> float:
        """Largest fraction in (0, 1] of the step ``dx`` [m] from positions ``x`` [m] that
        keeps the term valid, at edge rest lengths ``rest`` [m] (those of the evaluation at
        ``x``)."""
        return 1.0

    def check_state(self, x: np.ndarray) -> None:
        """Raise ValueError when positions ``x`` [m] are outside the term's domain (e.g.
        rods that already pass through each other)."""
        return None
