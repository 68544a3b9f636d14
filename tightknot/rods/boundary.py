"""Boundary conditions and loads along a load path t in [0, 1].

Clamped end (position and material frame), pinned end, prescribed end displacement and
rotation along the path, dead end force, and rest-length change along the path (for
growth/shrink continuation). Constrained dofs are eliminated from the Newton system; their
values are prescribed by :meth:`BoundaryConditions.apply`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tightknot.rods import frames
from tightknot.rods.model import Model

PathVec = Callable[[float], np.ndarray]
#: A held vertex's component values [m]: fixed, or a function of the load parameter t.
HeldValues = np.ndarray | Callable[[float], np.ndarray]


def _as_path_vec(value: np.ndarray | PathVec | None, name: str) -> PathVec | None:
    """A callable t -> (3,) from a callable, or from a final value reached linearly."""
    if value is None or callable(value):
        return value
    v = np.asarray(value, dtype=np.float64)
    if v.shape != (3,) or not np.isfinite(v).all():
        raise ValueError(f"{name} must be a finite 3-vector or a callable of t, got {value!r}")
    return lambda t: t * v


def rotation_matrix(rotvec: np.ndarray) -> np.ndarray:
    """Rotation matrix of a rotation vector (axis times angle [rad]), Rodrigues' formula."""
    rv = np.asarray(rotvec, dtype=np.float64)
    ang = float(np.linalg.norm(rv))
    if ang < 1e-15:
        return np.eye(3)
    k = rv / ang
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(ang) * kx + (1 - np.cos(ang)) * kx @ kx


@dataclass
class _Clamp:
    vertices: tuple[int, int]  # (end vertex, its neighbour)
    edge: int
    translation: PathVec | None
    rotation: PathVec | None  # t -> rotation vector about the end vertex
    x0: np.ndarray  # initial positions of the two vertices
    m1_0: np.ndarray | None  # initial material director of the clamped edge


@dataclass
class _Pin:
    vertex: int
    translation: PathVec | None
    x0: np.ndarray


class BoundaryConditions:
    """Constraints and loads on a model.

    Build, then pass to a solver. Indices are per rod (negative counts from the rod's end).
    """

    def __init__(self, model: Model, positions: np.ndarray | None = None) -> None:
        """``positions`` [m], (vertex_count, 3): where clamped and pinned vertices start
        (their prescribed motion is added to these); default the model's initial ones."""
        self.model = model
        pos = model.vertex_initial_position if positions is None else positions
        pos = np.array(pos, dtype=np.float64)
        if pos.shape != (model.vertex_count, 3) or not np.isfinite(pos).all():
            raise ValueError(f"positions must be finite with shape {(model.vertex_count, 3)}")
        self.positions = pos
        self._clamps: list[_Clamp] = []
        self._pins: list[_Pin] = []
        self._fixed_twist: list[int] = []
        self._components: list[tuple[int, tuple[int, ...]]] = []
        self._held: list[tuple[int, tuple[int, ...], HeldValues]] = []
        self._forces: list[tuple[int, PathVec]] = []
        self._rest_scale: list[tuple[np.ndarray, Callable[[float], float]]] = []

    # -- helpers -------------------------------------------------------------------------
    def _rod(self, rod: int):
        if not (0 <= rod < len(self.model.rods)):
            raise ValueError(f"rod must be in [0, {len(self.model.rods) - 1}], got {rod}")
        return self.model.rods[rod]

    def _vertex(self, rod: int, vertex: int) -> int:
        info = self._rod(rod)
        n = info.vertex_count
        if not (-n <= vertex < n):
            raise ValueError(f"vertex must be in [{-n}, {n - 1}] for rod {rod}, got {vertex}")
        return info.vertex_start + (vertex % n)

    # -- constraints ---------------------------------------------------------------------
    def clamp(
        self,
        rod: int = 0,
        end: str = "start",
        translation: np.ndarray | PathVec | None = None,
        rotation: np.ndarray | PathVec | None = None,
    ) -> BoundaryConditions:
        """Clamp an end of an open rod: its two end vertices and its end edge's material frame.

        ``translation`` [m] and ``rotation`` (rotation vector [rad], about the end vertex)
        are final values reached linearly along the path, or callables of t.
        """
        info = self._rod(rod)
        if info.closed:
            raise ValueError("clamp applies to open rods only")
        if end not in ("start", "end"):
            raise ValueError(f"end must be 'start' or 'end', got {end!r}")
        if end == "start":
            vs = (info.vertex_start, info.vertex_start + 1)
            edge = info.edge_start
        else:
            last = info.vertex_start + info.vertex_count - 1
            vs = (last, last - 1)
            edge = info.edge_start + info.edge_count - 1
        x0 = self.positions[list(vs)].copy()
        self._clamps.append(_Clamp(vs, edge, _as_path_vec(translation, "translation"),
                                   _as_path_vec(rotation, "rotation"), x0, None))
        return self

    def pin(
        self, rod: int = 0, vertex: int = 0, translation: np.ndarray | PathVec | None = None
    ) -> BoundaryConditions:
        """Fix a vertex's position (free to rotate), optionally moved along the path [m]."""
        v = self._vertex(rod, vertex)
        x0 = self.positions[v].copy()
        self._pins.append(_Pin(v, _as_path_vec(translation, "translation"), x0))
        return self

    def fix_components(
        self, rod: int = 0, vertex: int = 0, components: tuple[int, ...] = (1, 2)
    ) -> BoundaryConditions:
        """Fix some coordinates (0 = x, 1 = y, 2 = z) of a vertex at their initial values:
        a vertex sliding along an axis, or a gauge that removes a rigid rotation."""
        v = self._vertex(rod, vertex)
        comps = tuple(int(c) for c in components)
        if not comps or any(c not in (0, 1, 2) for c in comps):
            raise ValueError(
                f"components must be a non-empty subset of (0, 1, 2), got {components}")
        self._components.append((v, comps))
        return self

    def hold_components(
        self, rod: int = 0, vertex: int = 0, components: tuple[int, ...] = (1, 2),
        values: tuple[float, ...] | HeldValues = (0.0, 0.0),
    ) -> BoundaryConditions:
        """Fix some coordinates of a vertex at given ``values`` [m] (or at ``values(t)``
        along the load path), written into the state at every load step: a vertex held on
        an axis, as a grip holds a rod's tail, or on a plane that moves."""
        self.fix_components(rod, vertex, components)
        v, comps = self._components[-1]
        if callable(values):
            self._held.append((v, comps, values))
            return self
        vals = np.asarray(values, dtype=np.float64).reshape(-1)
        if vals.size != len(comps) or not np.isfinite(vals).all():
            raise ValueError(f"values must be {len(comps)} finite numbers "
                             f"(one per component), got {values!r}")
        self._held.append((v, comps, vals))
        return self

    def fix_twist(self, rod: int = 0, edge: int = 0) -> BoundaryConditions:
        """Fix the twist angle of one edge (e.g. no end twist of a pulled knot)."""
        info = self._rod(rod)
        n = info.edge_count
        if not (-n <= edge < n):
            raise ValueError(f"edge must be in [{-n}, {n - 1}] for rod {rod}, got {edge}")
        if self.model.twist:
            self._fixed_twist.append(info.edge_start + (edge % n))
        return self

    # -- loads ---------------------------------------------------------------------------
    def force(
        self, rod: int = 0, vertex: int = -1, force: np.ndarray | PathVec = (0.0, 0.0, 0.0)
    ) -> BoundaryConditions:
        """Dead force [N] on a vertex: its final value reached linearly, or a callable of t."""
        v = self._vertex(rod, vertex)
        f = _as_path_vec(force, "force")
        self._forces.append((v, f))
        return self

    def rest_length_scale(
        self, scale: Callable[[float], float] | tuple[float, float], rod: int | None = None
    ) -> BoundaryConditions:
        """Scale rest lengths along the path: a callable of t, or (start, end) linearly."""
        if not callable(scale):
            s0, s1 = (float(v) for v in scale)
            if not (s0 > 0 and s1 > 0 and np.isfinite([s0, s1]).all()):
                raise ValueError(f"rest_length_scale must be finite and > 0, got {scale!r}")
            fn = lambda t, s0=s0, s1=s1: s0 + (s1 - s0) * t  # noqa: E731
        else:
            fn = scale
        edges = (np.arange(self.model.edge_count) if rod is None
                 else np.arange(self._rod(rod).edge_start,
                                self._rod(rod).edge_start + self._rod(rod).edge_count))
        self._rest_scale.append((edges, fn))
        return self

    # -- evaluation ----------------------------------------------------------------------
    def fixed_mask(self) -> np.ndarray:
        """Boolean mask of the constrained dofs, shape (dof_count,)."""
        m = self.model
        mask = np.zeros(m.dof_count, dtype=bool)
        for c in self._clamps:
            for v in c.vertices:
                mask[m.vertex_dof[v] + np.arange(3)] = True
            if m.twist:
                mask[m.edge_dof[c.edge]] = True
        for p in self._pins:
            mask[m.vertex_dof[p.vertex] + np.arange(3)] = True
        for e in self._fixed_twist:
            mask[m.edge_dof[e]] = True
        for v, comps in self._components:
            mask[m.vertex_dof[v] + np.array(comps)] = True
        return mask

    def edge_rest_length(self, t: float) -> np.ndarray:
        """Rest length of each edge at load parameter t [m]."""
        rest = self.model.edge_rest_length.copy()
        for edges, fn in self._rest_scale:
            s = float(fn(t))
            if not (np.isfinite(s) and s > 0):
                raise ValueError(f"rest-length scale at t={t} must be finite and > 0, got {s}")
            rest[edges] *= s
        return rest

    def external_force(self, t: float) -> np.ndarray:
        """Dead forces on the vertices at load parameter t [N], shape (vertex_count, 3)."""
        f = np.zeros((self.model.vertex_count, 3))
        for v, fn in self._forces:
            f[v] += fn(t)
        return f

    def prescribe_positions(self, t: float, x: np.ndarray) -> None:
        """Write the prescribed positions at load parameter t into ``x`` (in place)."""
        for c in self._clamps:
            tr = c.translation(t) if c.translation else np.zeros(3)
            rot = rotation_matrix(c.rotation(t)) if c.rotation else np.eye(3)
            pivot = c.x0[0]
            for k, v in enumerate(c.vertices):
                x[v] = pivot + tr + rot @ (c.x0[k] - pivot)
        for p in self._pins:
            x[p.vertex] = p.x0 + (p.translation(t) if p.translation else 0.0)
        for v, comps, vals in self._held:
            if callable(vals):
                vals = np.asarray(vals(t), dtype=np.float64).reshape(-1)
                if vals.size != len(comps) or not np.isfinite(vals).all():
                    raise ValueError(f"held components {comps} of vertex {v} at t = {t}: "
                                     f"{len(comps)} finite values needed, got {vals!r}")
            x[v, list(comps)] = vals

    def prescribe_twist(
        self, t: float, theta: np.ndarray, d1_ref: np.ndarray, t_ref: np.ndarray
    ) -> None:
        """Write the prescribed twist angles at load parameter t into ``theta`` (in place):
        each clamped edge's material director follows the end's rotation."""
        if not self.model.twist:
            return
        for c in self._clamps:
            if c.m1_0 is None:
                raise RuntimeError("call capture(state) before prescribing twist")
            rot = rotation_matrix(c.rotation(t)) if c.rotation else np.eye(3)
            target = rot @ c.m1_0
            theta[c.edge] = frames.signed_angle(d1_ref[c.edge][None], target[None],
                                                t_ref[c.edge][None])[0]

    def capture(self, d1_ref: np.ndarray, t_ref: np.ndarray, theta: np.ndarray) -> None:
        """Record the material directors the clamped edges start from (once, at t = 0)."""
        for c in self._clamps:
            if c.m1_0 is None:
                m1, _ = frames.material_frames(d1_ref[c.edge][None], t_ref[c.edge][None],
                                               theta[c.edge : c.edge + 1])
                c.m1_0 = m1[0]
