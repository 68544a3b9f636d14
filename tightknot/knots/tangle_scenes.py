"""Two-rod scenes: the clasp and the bends, each rod with its own diameter and material.

A scene builds, it never solves (:mod:`tightknot.loading.tangle_pull` pulls it). The start
curves are those of :func:`tightknot.knots.tangles.tangle_curves`, in units of the larger
rod diameter, resampled to ``nodes`` vertices of equal chords per rod. Rod 0 ("A") has
both ends toward -x, rod 1 ("B") both toward +x; the pull moves them apart along x.

Model levels: no twist dofs (``twist=False``: isotropic rods whose ends hold the position,
not the material frame, so the twist relaxes, as for the study's open knots); the contact
layer of :func:`tightknot.knots.scenes.contact_layer` between every pair of edges, of one
rod or of two. The compliant law is calibrated on two identical rods (the FEM's squeeze of
two equal sections): a pair of rods of different diameters or moduli takes the pair's
harmonic-mean modulus and its own radii, outside that calibration, and the scene says so
in ``info["warnings"]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from tightknot.contact.law import RadialComplianceLaw
from tightknot.contact.layer import ContactLayer
from tightknot.knots import curves, tangles
from tightknot.knots.scenes import (
    STUDY_DIAMETER,
    STUDY_MATERIAL,
    check_contact,
    contact_layer,
    contact_name,
)
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material, check_positive
from tightknot.rods.model import Model
from tightknot.rods.state import State

#: Names of the two rods in messages and outputs.
ROD_NAMES = ("A", "B")

#: Fewest vertices per rod: the twist regions and U-turns need a few edges per diameter.
MIN_NODES = 40


@dataclass
class TangleScene:
    """Two rods tangled, ready to be pulled.

    Attributes:
        kind: "clasp", "reef", "granny", "thief" or "grief".
        model, state: the rods (rod 0 = A, rod 1 = B) and their start.
        contact: the contact layer (within each rod and between the rods).
        diameters: rest diameter D0 of each rod [m].
        pull_directions: unit direction each rod's ends are pulled in, (2, 3).
        start_type: the tangle's invariants at the start (checked against the kind).
        info: scene parameters; ``info["warnings"]``: what leaves the calibrated range.
    """

    kind: str
    model: Model
    state: State
    contact: ContactLayer
    diameters: tuple[float, float]
    pull_directions: np.ndarray
    start_type: tangles.TangleType
    info: dict = field(default_factory=dict)

    @property
    def name(self) -> str:
        """The scene's name ("clasp", "reef_bend"...)."""
        return self.kind if self.kind == "clasp" else f"{self.kind}_bend"

    @property
    def ends(self) -> str:
        """Where the working ends are ("same" or "diagonal"; the parcel closure's)."""
        return tangles.working_ends(self.kind)

    def end_vertices(self) -> list[tuple[int, str, int]]:
        """The four pulled ends: (rod, "start"|"end", model vertex index of the end)."""
        out = []
        for r, info in enumerate(self.model.rods):
            out.append((r, "start", info.vertex_start))
            out.append((r, "end", info.vertex_start + info.vertex_count - 1))
        return out

    def rod_points(self, x: np.ndarray) -> list[np.ndarray]:
        """Each rod's vertex positions [m] out of the model's ``x`` (vertex_count, 3)."""
        return [x[info.vertex_slice] for info in self.model.rods]

    def tangle_type(self, x: np.ndarray) -> tangles.TangleType:
        """The tangle's invariants at positions ``x`` [m]
        (:func:`tightknot.knots.tangles.tangle_type`)."""
        return tangles.tangle_type(self.rod_points(x), list(self.pull_directions), self.ends)

    def end_distance(self, x: np.ndarray) -> float:
        """End-to-end distance [m]: the mean x of B's two ends less that of A's two."""
        e = self.end_vertices()
        return float(0.5 * (x[e[2][2], 0] + x[e[3][2], 0]) - 0.5 * (x[e[0][2], 0]
                                                                   + x[e[1][2], 0]))


def _material(mat: Material | None, name: str) -> Material:
    m = mat if mat is not None else STUDY_MATERIAL
    if not isinstance(m, Material):
        raise ValueError(f"{name} must be a tightknot.rods.Material, got {type(m)}")
    return m


def tangle_scene(
    kind: str,
    nodes: int = 100,
    diameter: float = STUDY_DIAMETER,
    material: Material | None = None,
    diameter_b: float | None = None,
    material_b: Material | None = None,
    geometry: tangles.TangleGeometry | None = None,
    contact: str = "compliant",
    law: RadialComplianceLaw | None = None,
    device: str = "cpu",
    curves_d0: tuple[np.ndarray, np.ndarray] | None = None,
    curves_m: tuple[np.ndarray, np.ndarray] | None = None,
) -> TangleScene:
    """A two-rod tangle of ``kind`` (module docstring).

    Args:
        kind: "clasp" or a bend ("reef", "granny", "thief", "grief").
        nodes: vertices per rod (>= :data:`MIN_NODES`).
        diameter, material: rod A's rest diameter D0 [m] and material (default the study's).
        diameter_b, material_b: rod B's (default rod A's).
        geometry: sizes of the start curves [units of the larger D0].
        contact: "compliant", "smoothed" or "rigid" (not "off": the rods would pass through
            each other).
        law: the compliant contact law (default the shipped calibration).
        device: Warp device.
        curves_d0: start curves of A and B instead of the built-in ones, in units of the
            larger D0 (their type must still be the kind's).
        curves_m: the user's start curves of A and B [m] (open, each U-shaped with both
            ends pulled one way), placed by :func:`tightknot.knots.tangles.pull_frame`;
            their type must be the kind's.
    """
    if kind != "clasp" and kind not in tangles.BENDS:
        raise ValueError(f"kind must be 'clasp' or one of {', '.join(tangles.BENDS)}, "
                         f"got {kind!r}")
    if not (isinstance(nodes, (int, np.integer)) and not isinstance(nodes, bool)
            and nodes >= MIN_NODES):
        raise ValueError(f"nodes must be a whole number >= {MIN_NODES} per rod, got {nodes!r}")
    d_a = check_positive("diameter", diameter, "m")
    d_b = d_a if diameter_b is None else check_positive("diameter_b", diameter_b, "m")
    mat_a = _material(material, "material")
    mat_b = mat_a if material_b is None else _material(material_b, "material_b")
    contact = check_contact(contact, law)
    if contact == "off":
        raise ValueError("contact='off' cannot hold a tangle (the rods pass through each "
                         "other); use 'compliant', 'smoothed' or 'rigid'")
    d_max = max(d_a, d_b)
    if curves_d0 is not None and curves_m is not None:
        raise ValueError("give curves_d0 or curves_m, not both")
    if curves_m is not None:
        raw = [c / d_max for c in tangles.pull_frame(*curves_m)]
    else:
        raw = curves_d0 if curves_d0 is not None else tangles.tangle_curves(kind, geometry)
    pts = [curves.resample_equal_chords(np.asarray(c, dtype=np.float64) * d_max, int(nodes))
           for c in raw]
    radii = [0.5 * d_a, 0.5 * d_b]
    for r, (p, d) in enumerate(zip(pts, (d_a, d_b), strict=True)):
        try:
            curves.check_no_overlap(p, d, closed=False)
        except ValueError as err:
            raise ValueError(f"rod {ROD_NAMES[r]}: {err}") from None
        # Edges at most pi D0/4, half the contact's exclusion window, as for the one-rod
        # scenes (tightknot.knots.scenes._check_edge_length: longer neighbouring edges
        # would pair up as a contact and their shared vertex read as an intersection).
        edge = float(np.linalg.norm(p[1] - p[0]))
        limit = 0.25 * math.pi * d
        if edge > limit:
            raise ValueError(f"rod {ROD_NAMES[r]}: nodes={nodes} gives edges of {edge / d:.3g} "
                             f"D0, above pi/4 D0: give nodes >= "
                             f"{math.ceil((nodes - 1) * edge / limit) + 1}")
    gap, i, vi, j, vj = tangles.rod_overlaps(pts, radii)
    if gap < 0.0:
        raise ValueError(f"rods {ROD_NAMES[i]} and {ROD_NAMES[j]} overlap at the start: vertex "
                         f"{vi} of {ROD_NAMES[i]} is {gap + radii[i] + radii[j]:.4g} m from "
                         f"{ROD_NAMES[j]} (near its vertex {vj}), less than the sum of their "
                         f"radii {radii[i] + radii[j]:.4g} m")
    directions = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    start_type = tangles.tangle_type(pts, list(directions), tangles.working_ends(kind))
    if not start_type.matches(kind):
        lk, comp, closure = tangles.EXPECTED[kind]
        raise ValueError(f"the start curves are not a {kind}: {start_type.label()}, expected "
                         f"|lk| {lk}, rods {comp}" + (f", closure {closure}" if closure else ""))
    b = RodBuilder(twist=False)
    b.add_rod(pts[0], d_a, mat_a)
    b.add_rod(pts[1], d_b, mat_b)
    model = b.finalize(device)
    state = State.initial(model)
    layer = contact_layer(model, contact, law)
    warnings = []
    if d_a != d_b or mat_a != mat_b:
        warnings.append("the rods differ in diameter or material: the contact law between "
                        "them is calibrated on two identical rods (the pair takes the "
                        "harmonic-mean modulus and its own radii)")
    return TangleScene(kind, model, state, layer, (d_a, d_b), directions, start_type,
                       info={"nodes": int(nodes), "contact": contact_name(contact),
                             "geometry": (geometry or tangles.TangleGeometry()).__dict__,
                             "warnings": warnings})
