"""Builds a :class:`~tightknot.rods.model.Model` from rods given as vertex positions.

The rods are straight at rest (zero rest curvature), isotropic with a circular section
and no intrinsic twist (physics.md sec. 1): the given positions are the initial shape,
the rest lengths are the initial edge lengths unless given. Every check happens here,
before any kernel runs, and names the parameter and its valid range.
"""

from __future__ import annotations

import math

import numpy as np

from tightknot.rods.material import Material, check_positive, second_moment, section_area
from tightknot.rods.model import Model, RodInfo

#: An edge shorter than this fraction of the rod's mean edge is "coincident vertices".
_COINCIDENT_FRACTION = 1e-6


class RodBuilder:
    """Collects rods, then :meth:`finalize` makes the static model.

    Example:
        >>> b = RodBuilder()
        >>> b.add_rod(np.c_[np.linspace(0, 1, 11), np.zeros(11), np.zeros(11)], diameter=0.01)
        0
        >>> model = b.finalize()
    """

    def __init__(self, twist: bool = True) -> None:
        """``twist``: give edges a twist degree of freedom (off: isotropic rods whose
        twist relaxes, e.g. free or twist-free ends; the twist energy is then zero)."""
        self.twist = bool(twist)
        self._rods: list[dict] = []

    def add_rod(
        self,
        positions: np.ndarray,
        diameter: float,
        material: Material | None = None,
        closed: bool = False,
        rest_length: float | None = None,
        edge_rest_lengths: np.ndarray | None = None,
        link_offset: int = 0,
    ) -> int:
        """Add a rod and return its index.

        Args:
            positions: vertex positions [m], shape (N, 3); N >= 3 (open) or >= 3 (closed).
                For a closed rod the last vertex joins the first (not repeated).
            diameter: rest diameter D0 [m], > 0.
            material: elastic material (default: the study's elastomer).
            closed: closed (periodic) rod.
            rest_length: total rest length L0 [m]; edges get rest lengths proportional
                to their initial lengths. Default: the initial length.
            edge_rest_lengths: rest length of each edge [m] (overrides ``rest_length``).
            link_offset: closed rods only: excess link in whole turns added to the
                reference twist of the closing joint (0 = frame joined with no excess twist).
        """
        try:
            if np.iscomplexobj(positions):
                raise TypeError("complex")
            pts = np.asarray(positions, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError("positions must be a real (N, 3) array of numbers [m]") from None
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise ValueError(f"positions must have shape (N, 3), got {pts.shape}")
        n = pts.shape[0]
        if n < 3:
            raise ValueError(f"positions must hold at least 3 vertices for a rod, got {n}")
        bad = ~np.isfinite(pts).all(axis=1)
        if bad.any():
            raise ValueError(
                f"positions must be finite; vertex {int(np.argmax(bad))} is {pts[bad][0]}"
            )
        d0 = check_positive("diameter", diameter, "m")
        with np.errstate(over="ignore"):
            sizes_ok = np.isfinite([section_area(d0), second_moment(d0)]).all() if d0 < 1e75 \
                else False
        if not sizes_ok:
            raise ValueError(f"diameter must be > 0 m and small enough for D^4 to be finite, "
                             f"got {diameter!r}")
        mat = material if material is not None else Material()
        if not isinstance(mat, Material):
            raise ValueError(f"material must be a tightknot.rods.Material, got {type(mat)}")
        # E I and E A must be positive floats: D^4 or E (D^4) can underflow to 0, and a rod
        # with no bending stiffness gives the solver a zero force scale (residual NaN).
        try:
            emod = float(mat.youngs_modulus)
        except (TypeError, ValueError):
            raise ValueError("material.youngs_modulus must be a number [Pa], got "
                             f"{mat.youngs_modulus!r}") from None
        ei = emod * second_moment(d0)
        ea = emod * section_area(d0)
        if not (math.isfinite(ei) and ei > 0.0 and math.isfinite(ea) and ea > 0.0):
            raise ValueError(f"diameter {diameter!r} m and youngs_modulus "
                             f"{mat.youngs_modulus!r} Pa give a bending stiffness E I = {ei!r} "
                             "N m^2: it must be finite and > 0 (D^4 or E D^4 underflows)")
        closed = bool(closed)
        with np.errstate(over="ignore", invalid="ignore"):
            edges = np.diff(np.vstack([pts, pts[:1]]) if closed else pts, axis=0)
            lengths = np.linalg.norm(edges, axis=1)
        if not np.isfinite(lengths).all():
            raise ValueError("positions are too large: edge lengths overflow float64")
        mean = lengths.mean()
        short = lengths <= _COINCIDENT_FRACTION * mean
        if mean <= 0.0 or short.any():
            k = int(np.argmax(short)) if short.any() else 0
            raise ValueError(
                f"positions has coincident vertices {k} and {(k + 1) % n} "
                f"(edge length {lengths[k]:.3g} m; edges must be > {_COINCIDENT_FRACTION:g} "
                "x the mean edge length)"
            )
        if edge_rest_lengths is not None:
            rest = np.asarray(edge_rest_lengths, dtype=np.float64)
            if rest.shape != lengths.shape:
                raise ValueError(
                    f"edge_rest_lengths must have shape {lengths.shape}, got {rest.shape}"
                )
            if not (np.isfinite(rest).all() and (rest > 0).all()):
                raise ValueError("edge_rest_lengths must be finite and > 0 m")
        elif rest_length is not None:
            l0 = check_positive("rest_length", rest_length, "m")
            with np.errstate(over="ignore"):
                rest = lengths * (l0 / lengths.sum())
            if not (np.isfinite(rest).all() and (rest > 0).all()):
                raise ValueError(f"rest_length {rest_length!r} m gives edge rest lengths that "
                                 "are not finite and > 0 for these positions")
        else:
            rest = lengths.copy()
        try:
            lo = float(link_offset)
        except (TypeError, ValueError):
            lo = math.nan
        if not math.isfinite(lo) or lo != round(lo):
            raise ValueError(f"link_offset must be a whole number of turns, got {link_offset!r}")
        if lo and not closed:
            raise ValueError("link_offset applies to closed rods only")
        self._rods.append(
            dict(pts=pts, d0=d0, mat=mat, closed=closed, rest=rest, link=int(lo))
        )
        return len(self._rods) - 1

    def finalize(self, device: str = "cpu",
                 mirror_rod_pairs: tuple[tuple[int, int], ...] = ()) -> Model:
        """Make the model and upload its arrays to Warp ``device`` ("cpu", "cuda:0").
        ``mirror_rod_pairs``: pairs of rods that are one body's mirror images in a
        symmetric scene, never in contact (:attr:`Model.mirror_rod_pairs`)."""
        if not self._rods:
            raise ValueError("no rods: call add_rod() before finalize()")
        pairs = []
        for pair in mirror_rod_pairs:
            a, b = (int(i) for i in pair)
            if not (0 <= a < len(self._rods) and 0 <= b < len(self._rods) and a != b):
                raise ValueError(f"mirror_rod_pairs: {pair!r} is not a pair of two of the "
                                 f"{len(self._rods)} rods (indices 0 to "
                                 f"{len(self._rods) - 1})")
            pairs.append((min(a, b), max(a, b)))
        per = 4 if self.twist else 3
        rods: list[RodInfo] = []
        cols: dict[str, list[np.ndarray]] = {k: [] for k in (
            "vdof", "edof", "ev", "erest", "emua", "erad", "erot", "erod", "jv", "je", "jb",
            "jt", "jq", "vmass", "vrod", "pos", "jlink")}
        v0 = e0 = j0 = dof0 = 0
        for r, rod in enumerate(self._rods):
            pts, d0, mat, closed, rest = rod["pts"], rod["d0"], rod["mat"], rod["closed"], rod[
                "rest"]
            n = pts.shape[0]
            ne = n if closed else n - 1
            k = np.arange(n)
            vdof = dof0 + per * k
            edof = (dof0 + 4 * np.arange(ne) + 3) if self.twist else -np.ones(ne, dtype=np.int64)
            ndof = per * n - (1 if (self.twist and not closed) else 0)
            ev = np.stack([k[:ne], (k[:ne] + 1) % n], axis=1) + v0
            if closed:
                jc = k
                je = np.stack([(jc - 1) % n, jc], axis=1)
                jv = np.stack([(jc - 1) % n, jc, (jc + 1) % n], axis=1)
            else:
                jc = k[1:-1]
                je = np.stack([jc - 1, jc], axis=1)
                jv = np.stack([jc - 1, jc, jc + 1], axis=1)
            nj = jc.shape[0]
            a0, i0 = section_area(d0), second_moment(d0)
            rho = mat.density
            # Lumped vertex mass: rho A0 over the vertex's Voronoi rest length.
            vor = np.zeros(n)
            np.add.at(vor, ev[:, 0] - v0, 0.5 * rest)
            np.add.at(vor, ev[:, 1] - v0, 0.5 * rest)
            jlink = np.zeros(nj)
            if closed and rod["link"]:
                jlink[0] = 2.0 * math.pi * rod["link"]
            cols["vdof"].append(vdof)
            cols["edof"].append(edof)
            cols["ev"].append(ev)
            cols["erest"].append(rest)
            cols["emua"].append(np.full(ne, mat.neo_hookean_mu * a0))
            cols["erad"].append(np.full(ne, d0 / 2.0))
            # Twist inertia rho J0 l_bar with J0 = 2 I0 (polar moment of a circle).
            cols["erot"].append(rho * 2.0 * i0 * rest)
            cols["erod"].append(np.full(ne, r))
            cols["jv"].append(jv + v0)
            cols["je"].append(je + e0)
            cols["jb"].append(np.full(nj, mat.youngs_modulus * i0))
            cols["jt"].append(np.full(nj, mat.shear_modulus * 2.0 * i0))
            cols["jq"].append(np.full(nj, mat.thinning_exponent))
            cols["vmass"].append(rho * a0 * vor)
            cols["vrod"].append(np.full(n, r))
            cols["pos"].append(pts)
            cols["jlink"].append(jlink)
            rods.append(RodInfo(v0, n, e0, ne, j0, nj, closed, d0, mat))
            v0, e0, j0, dof0 = v0 + n, e0 + ne, j0 + nj, dof0 + ndof

        def cat(key: str, dtype: type) -> np.ndarray:
            return np.ascontiguousarray(np.concatenate(cols[key]).astype(dtype))

        vertex_dof = cat("vdof", np.int32)
        edge_dof = cat("edof", np.int32)
        edge_vertex = cat("ev", np.int32)
        joint_vertex = cat("jv", np.int32)
        joint_edge = cat("je", np.int32)
        xyz = np.arange(3)
        joint_dofs = np.concatenate(
            [(vertex_dof[joint_vertex][:, :, None] + xyz).reshape(-1, 9),
             edge_dof[joint_edge]], axis=1).astype(np.int32)
        edge_dofs = (vertex_dof[edge_vertex][:, :, None] + xyz).reshape(-1, 6).astype(np.int32)
        model = Model(
            rods=rods,
            twist=self.twist,
            vertex_dof=vertex_dof,
            edge_dof=edge_dof,
            dof_count=dof0,
            edge_vertex=edge_vertex,
            edge_rest_length=cat("erest", np.float64),
            edge_mu_area=cat("emua", np.float64),
            edge_radius=cat("erad", np.float64),
            edge_rot_inertia=cat("erot", np.float64),
            edge_rod=cat("erod", np.int32),
            joint_vertex=joint_vertex,
            joint_edge=joint_edge,
            joint_bend_stiffness=cat("jb", np.float64),
            joint_twist_stiffness=cat("jt", np.float64),
            joint_thinning_exponent=cat("jq", np.float64),
            vertex_mass=cat("vmass", np.float64),
            vertex_rod=cat("vrod", np.int32),
            joint_dofs=np.ascontiguousarray(joint_dofs),
            edge_dofs=np.ascontiguousarray(edge_dofs),
            vertex_initial_position=cat("pos", np.float64),
            joint_link_offset=cat("jlink", np.float64),
            device=str(device),
            mirror_rod_pairs=tuple(sorted(set(pairs))),
        )
        model.upload()
        return model
