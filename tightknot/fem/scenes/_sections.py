"""Profiles along a rod of a two-body FEM scene: per node layer the section's area ratio
A/A0, the contact width fraction L_c and the peak pressure, and the contact patch map.

A rod here is a section mesh extruded along its rest axis (:func:`tightknot.fem.mesh.extrude`),
``points_per_layer`` points per layer, the layers in order along the axis; the scene may
then place or bend it. The modelled piece of the section is a half or a quarter of the
disk (symmetry planes), and its lateral boundary a chain of nodes from the contact centre
(on a symmetry line) around the modelled arc. By the symmetry the fractions measured on the
piece are those of the whole section.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mesh import lateral_faces
from ._pair import LOADED_FRACTION


def boundary_chain(section_points: np.ndarray, edges: np.ndarray, centre: np.ndarray
                   ) -> np.ndarray:
    """Section-node indices of the open boundary polyline ``edges`` (n, 2), in order from
    the node nearest to ``centre`` [m] (an end of the chain: a symmetry line's point)."""
    start = int(np.argmin(np.linalg.norm(section_points[:, :2] - centre, axis=1)))
    neighbours: dict[int, list[int]] = {}
    for a, b in np.asarray(edges):
        neighbours.setdefault(int(a), []).append(int(b))
        neighbours.setdefault(int(b), []).append(int(a))
    if len(neighbours.get(start, [])) != 1:
        raise ValueError("the contact centre must be an end of the section's boundary chain")
    chain = [start]
    while True:
        nxt = [n for n in neighbours[chain[-1]] if n not in chain[-2:]]
        if not nxt:
            return np.asarray(chain)
        chain.append(nxt[0])


def loaded_arc(arc: np.ndarray, p: np.ndarray) -> float:
    """Loaded length [m] of a boundary polyline from its contact centre: ``arc`` the
    cumulative lengths from the centre (arc[0] = 0), ``p`` the pressures (zero where
    unloaded). An edge with both ends loaded counts whole; an edge with one loaded end up
    to the edge that p^2, linear near a smooth contact's edge (Johnson 1985 eq. 4.44),
    extrapolates from the loaded end and its loaded neighbour (half the edge where that
    does not fall), as :func:`tightknot.fem.measure.edge_position` does. Interior gaps
    (a ridge with an inner gap) are left out."""
    total = 0.0
    n = len(arc)
    for i in range(n - 1):
        length = float(arc[i + 1] - arc[i])
        a, b = p[i] > 0.0, p[i + 1] > 0.0
        if a and b:
            total += length
        elif a or b:
            k, m = (i, i - 1) if a else (i + 1, i + 2)
            if k == 0:
                m = 1  # the centre's mirror neighbour is node 1's image
            if 0 <= m < n and p[m] > p[k]:
                reach = p[k] ** 2 / (p[m] ** 2 - p[k] ** 2) * abs(arc[k] - arc[m])
                total += float(np.clip(reach, 0.0, length))
            else:
                total += 0.5 * length
    return total


@dataclass
class RodSections:
    """Layout of one extruded rod in a scene's mesh (module docstring).

    ``offset``: index of the rod's first point in the body mesh; ``points_per_layer``;
    ``quads``: the section's quads (section-node indices); ``chain``: the lateral
    boundary's section nodes from the contact centre (:func:`boundary_chain`);
    ``s_rest``: rest axial coordinate [m] of each layer; ``phi_rest``: rest angle [rad] of
    each chain node from the contact centre around the section axis; ``area0``: rest area
    [m^2] of the modelled piece.
    """

    offset: int
    points_per_layer: int
    quads: np.ndarray
    chain: np.ndarray
    s_rest: np.ndarray
    phi_rest: np.ndarray
    area0: float

    @classmethod
    def from_section(cls, section: object, radius: float, centre: np.ndarray,
                     s_rest: np.ndarray, offset: int) -> RodSections:
        """The layout of ``section`` (a FElupe quad mesh of radius ``radius`` [m], contact
        centre ``centre`` [m] on its boundary) extruded through ``s_rest`` [m]."""
        pts = np.asarray(section.points)[:, :2]
        quads = np.asarray(section.cells)
        chain = boundary_chain(pts, lateral_faces(section, radius), np.asarray(centre))
        c = np.asarray(centre, dtype=float) / np.linalg.norm(centre)
        cross = c[0] * pts[chain, 1] - c[1] * pts[chain, 0]
        phi = np.abs(np.arctan2(cross, pts[chain] @ c))
        return cls(offset, len(pts), quads, chain, np.asarray(s_rest, dtype=float), phi,
                   _quad_areas(np.column_stack([pts, np.zeros(len(pts))]), quads).sum())

    @property
    def layers(self) -> int:
        """Number of node layers."""
        return len(self.s_rest)

    def layer_points(self, j: int) -> np.ndarray:
        """Body-mesh indices of layer ``j``'s points."""
        start = self.offset + j * self.points_per_layer
        return np.arange(start, start + self.points_per_layer)

    def profile(self, x: np.ndarray, pressure: np.ndarray, youngs_modulus: float,
                diameter: float, layers: int | None = None) -> list[dict[str, float]]:
        """Per layer (the first ``layers``): ``s_over_d0`` (rest), ``area_ratio`` A/A0 (the
        deformed layer's quad areas in 3D), ``contact_fraction`` L_c (the loaded arc over
        the deformed perimeter, :func:`loaded_arc`; a node is loaded above
        ``LOADED_FRACTION`` of the rod's peak pressure) and ``peak_pressure_over_e``.
        ``x`` [m] and ``pressure`` [Pa] over all body points."""
        p_rod = pressure[self.offset:self.offset + self.layers * self.points_per_layer]
        p_cut = LOADED_FRACTION * float(p_rod.max()) if p_rod.size else 0.0
        rows = []
        for j in range(self.layers if layers is None else layers):
            idx = self.layer_points(j)
            ring = x[idx[self.chain]]
            arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(ring, axis=0),
                                                                  axis=1))])
            p = pressure[idx[self.chain]]
            p = np.where(p > p_cut, p, 0.0) if p_cut > 0.0 else np.zeros_like(p)
            rows.append({
                "s_over_d0": float(self.s_rest[j]) / diameter,
                "area_ratio": float(_quad_areas(x[idx], self.quads).sum()) / self.area0,
                "contact_fraction": loaded_arc(arc, p) / float(arc[-1]),
                "peak_pressure_over_e": float(pressure[idx].max()) / youngs_modulus,
            })
        return rows

    def patch(self, pressure: np.ndarray, youngs_modulus: float, diameter: float
              ) -> dict[str, list[float]]:
        """The contact patch map: the loaded lateral nodes' rest positions (``s_over_d0``
        along the axis, ``phi_deg`` around the section from the contact centre) and their
        pressures ``p_over_e``."""
        idx = (self.offset + np.arange(self.layers)[:, None] * self.points_per_layer
               + self.chain[None, :])
        p = pressure[idx]
        peak = float(p.max()) if p.size else 0.0
        on = p > LOADED_FRACTION * peak if peak > 0.0 else np.zeros(p.shape, dtype=bool)
        layer, node = np.nonzero(on)
        return {"s_over_d0": (self.s_rest[layer] / diameter).tolist(),
                "phi_deg": np.degrees(self.phi_rest[node]).tolist(),
                "p_over_e": (p[on] / youngs_modulus).tolist()}


def contact_half_length(profile: list[dict[str, float]]) -> float:
    """Contact half-length along a rod [D0]: the rest position of its last loaded layer
    (0 where none is loaded)."""
    loaded = [r["s_over_d0"] for r in profile if r["contact_fraction"] > 0.0]
    return max(loaded) if loaded else 0.0


def _quad_areas(corners_of: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """Areas [m^2] of quads with 3D corners (the diagonals' cross product: exact for a
    planar quad, the mean projected area of a warped one)."""
    c = np.asarray(corners_of)[quads]
    return 0.5 * np.linalg.norm(np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]), axis=1)
