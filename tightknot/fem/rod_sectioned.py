"""The FEM's indent and wrap scenes with the rod model at the sectioned contact level.

The scenes, load levels and boundary conditions of :mod:`tightknot.fem.rod_model`, with the
contact of :class:`tightknot.contact.sectioned.SectionedLayer`: the compared rod carries its
sections as dofs, the rigid counter-bodies are pinned rods with rigid round sections
(``rigid_rods``), so that no pair law needs scaling. Each level reports the keys of the
compliant level's runs (force, A/A0 and peak pressure at the mid section, the wrap's line
load and curvature) and, read off the sections, the contact width fraction L_c of the mid
section.

The wrap's axis: as in the FEM (:func:`tightknot.fem.scenes.wrap.nominal_axis`), the far
fibre (the boundary point opposite the contact, here the mid section's deformed boundary
at the angle facing away from the cylinder) moved toward the cylinder by the stretched
radius r0 lambda^(-1/2); line load per length and curvature are taken on it.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from .material import ROD_DIAMETER, YOUNGS_MODULUS
from .rod_model import EDGES_PER_D0, WRAP_START_OVERLAP, _solve_levels, indent_scene, wrap_scene

#: Half-width [D0] of the window the wrap's windowed mid line load sums over.
WINDOW: float = 0.25


def _layer(model: Any, section: Any, rigid_rods: tuple[int, ...], gauss_points: int = 2
           ) -> Any:
    from tightknot.contact.sectioned import SectionedLayer

    return SectionedLayer(model, section, rigid_rods=rigid_rods, gauss_points=gauss_points)


def _report(layer: Any, system: Any) -> dict[str, np.ndarray]:
    st = system.state
    return layer.section_report(st.x, st.extra, st.frames, system.rest)


def _outward_profile(rep: dict[str, np.ndarray], verts: np.ndarray, h: float,
                     diameter: float) -> list[dict[str, float]]:
    """A/A0, L_c and p_max/E at the Gauss circles of the edges from the vertex before the
    middle ``verts[0]`` outward along ``verts`` (rest edge length ``h`` [m]), at rest arc
    length ``s_over_d0`` from the middle: the rows of the FEM's ``profile_a``
    (:func:`tightknot.fem.profile_compare.circle_profile`; the edge before the middle
    puts s = 0 inside the profile)."""
    from tightknot.fem.profile_compare import circle_profile

    verts = np.concatenate([[verts[0] - 1], verts])
    return circle_profile(rep, verts, (np.arange(verts.size) - 1.0) * h, diameter)


def rod_indent_sectioned(w_levels: list[float], diameter: float = ROD_DIAMETER,
                         youngs_modulus: float = YOUNGS_MODULUS, length_over_d0: float = 3.0,
                         section: Any = None, edges_per_d0: int = EDGES_PER_D0,
                         gauss_points: int = 2) -> dict[str, Any]:
    """The indent scene (:func:`tightknot.fem.rod_model.rod_indent`) at the sectioned
    level (``section``: its :class:`~tightknot.contact.sectioned.SectionSettings`;
    ``edges_per_d0`` and ``gauss_points`` per edge: the rod's resolution). Per
    level: ``force`` [N] on the upper indenter, ``area_ratio_mid``, ``peak_pressure_over_e``,
    ``contact_width_fraction_mid`` (both indenters' contacts), ``axial_stretch_mid``;
    ``profile_a``: A/A0, L_c and p_max/E per vertex from the middle outward."""
    start = time.perf_counter()
    d0 = diameter
    scene = indent_scene(diameter, youngs_modulus, length_over_d0,
                         edges_per_d0=edges_per_d0)
    system, load, model = scene.system, scene.load, scene.model
    n_rod, mid, half = scene.n_rod, scene.mid, scene.half
    layer = _layer(model, section, (1, 2), gauss_points)
    system.add_term(layer)
    up_v = scene.obs_v
    rod_v0 = model.rods[0].vertex_start

    def measure(w: float) -> dict[str, Any]:
        x = system.state.x
        force = -float(system.term_gradient(layer)[up_v, 1].sum())
        rep = _report(layer, system)
        e = np.linalg.norm(np.diff(x[rod_v0:rod_v0 + n_rod + 1], axis=0), axis=1)
        stretch = float(0.5 * (e[mid - 1] + e[mid]) / (2.0 * half / n_rod))
        v = rod_v0 + mid
        return {
            "w_over_d0": w / d0, "approach_over_d0": 2.0 * w / d0, "force": force,
            "force_over_e_d0sq": force / (youngs_modulus * d0**2),
            "axial_stretch_mid": stretch, "area_ratio_mid": float(rep["area_ratio"][v]),
            "peak_pressure_over_e": float(rep["peak_pressure_over_E"][v]),
            "contact_width_fraction_mid": float(rep["contact_width_fraction"][v]),
            "contact_weight_sum_mean": rep["contact_weight_sum_mean"],
            # from the middle outward, as the FEM's quarter rod (z >= 0) reports it
            "profile_a": _outward_profile(rep, np.arange(v, rod_v0 + n_rod + 1),
                                          2.0 * half / n_rod, d0),
        }

    rows = _solve_levels(system, load, list(w_levels), measure)
    return {"steps": rows, "wall_time_s": time.perf_counter() - start,
            "vertices": int(model.vertex_count), "contact": "sectioned",
            "section_modes": layer.section.max_mode, "penalty": layer.penalty}


def _vertex_section(layer: Any, system: Any, v: int
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """Vertex ``v`` of rod 0 at the state: its frame's t, d1, d2 (of the edge that stores its
    section), its section's coefficients [m] and mean radius R [m] (the area's, thinned by
    the stretch of the boundaries' centre line, incompressible)."""
    st = system.state
    m = layer.model
    k = layer.section.coeff_count
    last_edge = m.rods[0].edge_start + m.rods[0].edge_count - 1
    e = min(v - m.rods[0].vertex_start + m.rods[0].edge_start, last_edge)
    t, d1 = st.t_ref[e], st.d1_ref[e]
    c = st.extra[layer.vertex_offset[v]:layer.vertex_offset[v] + k]
    a, b = m.edge_vertex[e]
    centres = layer.boundary_centres(st.x, system.rest)
    lam = float(np.linalg.norm(centres[b] - centres[a]) / system.rest[e])
    return t, d1, np.cross(t, d1), c, math.sqrt(layer.edge_r0[e] ** 2 / lam - 0.5 * float(c @ c))


def far_fibre_axis(layer: Any, system: Any, verts: np.ndarray, axis_y: float,
                   r_stretched: float) -> np.ndarray:
    """The nominal axis at vertices ``verts`` of the wrapped rod (module docstring): the
    far fibre, opposite the direction to the cylinder axis (the line y = ``axis_y``, z = 0
    along x), moved toward it by ``r_stretched`` [m] (the far fibre of the section about
    its boundary's centre)."""
    from tightknot.contact.sectioned_reference import mode_basis

    st = system.state
    centres = layer.boundary_centres(st.x, system.rest)
    out = np.empty((len(verts), 3))
    for i, v in enumerate(verts):
        t, d1, d2, c, big_r = _vertex_section(layer, system, v)
        # the direction to the cylinder's axis (the x axis at y = axis_y), normal to t
        toward = np.array([0.0, axis_y - centres[v, 1], -centres[v, 2]])
        toward -= (toward @ t) * t
        away = -toward / np.linalg.norm(toward)
        phi = math.atan2(away @ d2, away @ d1)
        r = big_r + float(mode_basis(layer.modes, np.array([phi]))[0][0] @ c)
        out[i] = centres[v] + (r - r_stretched) * away
    return out


def axis_reading(axis: np.ndarray, force: float) -> tuple[float, float]:
    """On an axis through seven vertices centred on a wrap's middle (``axis`` [m]): the
    middle's line load, the contact force ``force`` [N] per its tributary length [N/m],
    and the axis's curvature there [1/m]."""
    from tightknot.knots.curvature import bergou_curvature

    seg = np.linalg.norm(np.diff(axis, axis=0), axis=1)
    return (float(force / (0.5 * (seg[2] + seg[3]))),
            float(bergou_curvature(axis, closed=False)[3]))


def _centroid_axis(layer: Any, system: Any, verts: np.ndarray) -> np.ndarray:
    """The centroids [m] of the deformed sections at vertices ``verts`` of rod 0: the
    boundary's centre x_v (:meth:`~tightknot.contact.sectioned.SectionedLayer.
    boundary_centres`) plus (1 / 3A) int r^3 (cos phi d1 + sin phi d2) dphi, A = (1/2) int r^2 dphi
    (the area centroid of a star-shaped section), by the midpoint rule on 720 angles."""
    from tightknot.contact.sectioned_reference import mode_basis

    centres = layer.boundary_centres(system.state.x, system.rest)
    phi = 2.0 * math.pi * (np.arange(720) + 0.5) / 720
    basis = mode_basis(layer.modes, phi)[0]
    out = np.empty((len(verts), 3))
    for i, v in enumerate(verts):
        _, d1, d2, c, big_r = _vertex_section(layer, system, v)
        r = big_r + basis @ c
        area = 0.5 * float(np.mean(r * r)) * 2.0 * math.pi
        mx = float(np.mean(r**3 * np.cos(phi))) * 2.0 * math.pi / (3.0 * area)
        my = float(np.mean(r**3 * np.sin(phi))) * 2.0 * math.pi / (3.0 * area)
        out[i] = centres[v] + mx * d1 + my * d2
    return out


def rod_wrap_sectioned(tension_levels: list[float], wrap_angle_deg: float = 90.0,
                       diameter: float = ROD_DIAMETER, youngs_modulus: float = YOUNGS_MODULUS,
                       length_over_d0: float = 4.5, section: Any = None,
                       edges_per_d0: int = EDGES_PER_D0, gauss_points: int = 2
                       ) -> dict[str, Any]:
    """The wrap scene (:func:`tightknot.fem.rod_model.rod_wrap`) at the sectioned level
    (``edges_per_d0``, ``gauss_points``: the resolution, as for the indent).
    Per tension level [N]: ``force_per_length_mid`` [N/m] (contact line load at the middle
    per length of the nominal axis), ``kappa_d0_mid`` (its curvature),
    ``approach_over_d0`` (of the nominal axis), ``area_ratio_mid``,
    ``peak_pressure_over_e``, ``contact_width_fraction_mid``, ``contact_force_total``;
    ``force_per_length_mid_window_over_e_d0`` (the vertices' contact forces across the
    centreline summed as vectors over +-``WINDOW`` D0 of the middle, per stretched
    length) and
    ``contact_axial_over_across_mid`` (within +-0.5 D0: the largest axial part of a
    vertex's contact force over the largest part across: the edges' thinning pull, as the
    traction of a frictionless contact is all across); ``profile_a``: A/A0, L_c and
    p_max/E per vertex from the middle outward (rest arc length ``s_over_d0``), the rows of
    the FEM's ``profile_a``."""
    from tightknot.knots.curvature import bergou_curvature

    start = time.perf_counter()
    d0 = diameter
    scene = wrap_scene(diameter, youngs_modulus, length_over_d0, wrap_angle_deg,
                       edges_per_d0=edges_per_d0)
    system, load, model = scene.system, scene.load, scene.model
    n_rod, mid, half = scene.n_rod, scene.mid, scene.half
    y_obs = d0 - WRAP_START_OVERLAP * d0
    layer = _layer(model, section, (1,), gauss_points)
    system.add_term(layer)
    rod_v, obs_v = scene.rod_v, scene.obs_v

    def measure(tension: float) -> dict[str, Any]:
        x = system.state.x
        g = system.term_gradient(layer)
        total = float(np.linalg.norm(g[obs_v].sum(axis=0)))
        rep = _report(layer, system)
        xr = x[rod_v]
        # the nominal circle's radius from the stretch of the boundaries' centre line
        xb = layer.boundary_centres(x, system.rest)[rod_v]
        e = np.linalg.norm(np.diff(xb, axis=0), axis=1)
        stretch = float(0.5 * (e[mid - 1] + e[mid]) / (2.0 * half / n_rod))
        r_str = 0.5 * d0 / math.sqrt(stretch)
        near = rod_v[mid - 3:mid + 4]
        nominal = far_fibre_axis(layer, system, near, y_obs, r_str)
        f_mid, kappa = axis_reading(nominal, float(np.linalg.norm(g[rod_v[mid]])))
        kappa_c = float(bergou_curvature(xr, closed=False)[mid])
        cent = _centroid_axis(layer, system, near)
        f_cent, kappa_cent = axis_reading(cent, float(np.linalg.norm(g[rod_v[mid]])))
        dist = math.hypot(y_obs - nominal[3, 1], nominal[3, 2])
        v = rod_v[mid]
        # the contact term's forces on the rod's vertices, split along and across its
        # centreline: the traction of a frictionless contact is across it, so an axial part
        # is the sections' pull on their own edges' stretch (they thin with it, a force pair
        # per edge), and the load across it summed over +-WINDOW D0 of the middle is a line
        # load that no single vertex aliases
        tang = np.gradient(xr, axis=0)
        tang /= np.linalg.norm(tang, axis=1)[:, None]
        gr = g[rod_v]
        axial = np.einsum("ij,ij->i", gr, tang)
        across_v = gr - axial[:, None] * tang
        across = np.linalg.norm(across_v, axis=1)
        h = 2.0 * half / n_rod
        k_win = max(1, int(round(WINDOW * d0 / h)))
        k_diag = max(1, int(round(0.5 * d0 / h)))
        win = slice(mid - k_win, mid + k_win + 1)
        near_half = slice(mid - k_diag, mid + k_diag + 1)
        # the vector sum: force couples between neighbouring vertices (a section's modes
        # turn with its edge) cancel in it
        f_win = float(np.linalg.norm(across_v[win].sum(axis=0))) / ((2 * k_win + 1) * h
                                                                     * stretch)
        top = float(across[near_half].max())
        return {
            "tension": tension, "tension_over_e_d0sq": tension / (youngs_modulus * d0**2),
            "approach_over_d0": (d0 - dist) / d0, "axial_stretch_mid": stretch,
            "contact_force_total": total, "force_per_length_mid": f_mid,
            "force_per_length_mid_over_e_d0": f_mid / (youngs_modulus * d0),
            "area_ratio_mid": float(rep["area_ratio"][v]), "kappa_d0_mid": kappa * d0,
            "kappa_d0_mid_centerline": kappa_c * d0,
            "kappa_d0_mid_centroid": kappa_cent * d0,
            "force_per_length_mid_centroid": f_cent,
            "peak_pressure_over_e": float(rep["peak_pressure_over_E"][v]),
            "contact_width_fraction_mid": float(rep["contact_width_fraction"][v]),
            "contact_weight_sum_mean": rep["contact_weight_sum_mean"],
            "force_per_length_mid_window_over_e_d0": f_win / (youngs_modulus * d0),
            "contact_axial_over_across_mid": (float(np.abs(axial[near_half]).max()) / top
                                              if top > 0.0 else 0.0),
            # from the middle outward, as the FEM's half rod (z >= 0) reports it
            "profile_a": _outward_profile(rep, rod_v[mid:], h, d0),
        }

    rows = _solve_levels(system, load, list(tension_levels), measure)
    return {"steps": rows, "wall_time_s": time.perf_counter() - start,
            "vertices": int(model.vertex_count), "contact": "sectioned",
            "section_modes": layer.section.max_mode, "penalty": layer.penalty}
