"""Per-vertex contact outputs of a state: overlap, contact width, pressure, section area.

Read off the contact layer's non-local pairs in contact and the calibrated law's fits
(:mod:`tightknot.contact.law`); a pure function of the positions and rest lengths.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tightknot.contact.layer import ContactLayer
from tightknot.contact.sectioned import SectionedLayer
from tightknot.rods.state import State

#: The sectioned level's per-circle outputs a report carries (:attr:`ContactReport.circles`).
CIRCLE_KEYS = ("circle_contact_width_fraction", "circle_peak_pressure_over_E",
               "edge_area_ratio", "circle_u", "edge_vertex")


@dataclass
class ContactReport:
    """Per-vertex contact outputs (see :func:`contact_report`).

    Attributes:
        overlap: largest pair overlap delta at the vertex [m] (0 when free).
        overlap_opposite: largest overlap from the opposite side [m].
        force_per_length: contact force per unit length on the vertex [N/m].
        half_width: line-contact half-width b [m].
        contact_width_fraction: L_c, fraction of the perimeter in contact [-].
        mean_pressure_over_E: mean contact pressure over E [-].
        peak_pressure_over_E: peak contact pressure over E [-].
        area_ratio: section area A/A0 from stretch and squeeze (incompressible) [-].
        pairs: contact point pairs (i, j) as vertex indices with their overlap [m].
        weight_sum_mean: the sectioned level's mean sum of a contact sample's passes'
            weights (one but inside a rod's exclusion ramp, past an open end or on the
            inside of a partner bent tighter than rho kappa about 0.7;
            docs/sectioned_level.md, "The partner's partition of unity on a bent
            partner"); None at the other levels and without contact.
        circles: the sectioned level's outputs per Gauss circle (the ``circle_...``,
            ``edge_area_ratio`` and ``edge_vertex`` entries of
            :meth:`~tightknot.contact.sectioned.SectionedLayer.section_report`); None at
            the other levels.
    """

    overlap: np.ndarray
    overlap_opposite: np.ndarray
    force_per_length: np.ndarray
    half_width: np.ndarray
    contact_width_fraction: np.ndarray
    mean_pressure_over_E: np.ndarray
    peak_pressure_over_E: np.ndarray
    area_ratio: np.ndarray
    pairs: np.ndarray
    weight_sum_mean: float | None = None
    circles: dict[str, np.ndarray] | None = None


def _segment_closest(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray,
                     q1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closest-point parameters (s, t) of segment pairs (rows), Ericson 2005 sec. 5.1.9."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a = np.einsum("ij,ij->i", d1, d1)
    e = np.einsum("ij,ij->i", d2, d2)
    f = np.einsum("ij,ij->i", d2, r)
    c = np.einsum("ij,ij->i", d1, r)
    b = np.einsum("ij,ij->i", d1, d2)
    denom = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denom > 1e-14 * a * e, np.clip((b * f - c * e) / denom, 0, 1), 0.0)
        t = (b * s + f) / e
        s = np.where(t < 0, np.clip(-c / a, 0, 1), np.where(t > 1, np.clip((b - c) / a, 0, 1), s))
        t = np.clip(t, 0, 1)
    return s, t


def contact_report(layer: ContactLayer, x: np.ndarray,
                   rest: np.ndarray | None = None, state: State | None = None
                   ) -> ContactReport:
    """Per-vertex contact outputs of the state ``x`` [m] with edge rest lengths ``rest``
    [m] (default: those of the layer's last evaluation), derived from the law's fits; at
    the sectioned level (:class:`tightknot.contact.sectioned.SectionedLayer`) the width,
    pressures, force and area come from the sections of ``state`` instead
    (:meth:`~tightknot.contact.sectioned.SectionedLayer.section_report`; the overlaps, of
    the nominal stretched radii, say how far the sections are flattened).

    For every non-local edge pair in contact, the closest points of the two segments give
    the distance d, the pair overlap delta = R - d (R = r_a + r_b, stretched radii) and the
    contact normal; each side takes the per-side approach w = delta/2 (identical rods,
    contact_law docstring). Per edge, the largest w (w1) and the largest from the opposite
    side (w2, normal more than 120 degrees away) are kept; a vertex takes the larger of its
    edges'. Then, from the calibrated fits (tightknot/data/contact_law.json):
    half-width b(w1); L_c = L_c,side(w1) + L_c,side(w2) (<= 1); mean pressure f_line(w1)/(2b);
    peak pressure blended from the line and point fits by the crossing angle; area
    A/A0 = (1/stretch)(1 - k_area (w_sq/D)^p) with w_sq = (w1 + w2)/2 (the calibration
    squeezes both sides; a one-sided contact counts half), stretch from the vertex's edges.
    A rigid-tube law reports no width, no pressure and the area of stretch alone.
    """
    m = layer.model
    law = layer.law
    n = m.vertex_count
    rest = layer.last_rest if rest is None else np.asarray(rest, dtype=np.float64)
    ev = m.edge_vertex
    e = x[ev[:, 1]] - x[ev[:, 0]]
    le = np.linalg.norm(e, axis=1)
    # the stretch that thins the sections: each edge's own, or the layer's window mean
    stretch_e = layer.section_stretch(x, rest)
    nu = np.array([0.0 if law.rigid else m.rods[r].material.poisson_ratio for r in m.edge_rod])
    radius_e = m.edge_radius * stretch_e ** (-nu)
    d0 = 2.0 * m.edge_radius
    pairs = layer.nonlocal_pairs(x, rest)  # not the pairs only the local barrier sees
    arcs = layer.broad_phase.arcs(rest)[0].numpy()
    w1 = np.zeros(m.edge_count)
    n1 = np.zeros((m.edge_count, 3))
    w2 = np.zeros(m.edge_count)
    xi_e = np.zeros(m.edge_count)
    pair_list = np.zeros((0, 3))
    if pairs.shape[0]:
        a, b = pairs[:, 0], pairs[:, 1]
        s, t = _segment_closest(x[ev[a, 0]], x[ev[a, 1]], x[ev[b, 0]], x[ev[b, 1]])
        # A pair straddling the exclusion window touches only through its points farther
        # apart along the rod than the window (on a coarse rod, whole segments a few edges
        # apart would read as a contact of neighbours).
        partial, _, sp, tp = layer.checks.window_closest(x, pairs, arcs)
        s[partial], t[partial] = sp, tp
        pa = x[ev[a, 0]] + s[:, None] * e[a]
        pb = x[ev[b, 0]] + t[:, None] * e[b]
        dvec = pb - pa
        dist = np.linalg.norm(dvec, axis=1)
        big_r = radius_e[a] + radius_e[b]
        xo = big_r - dist  # pair overlap delta
        keep = xo > 0.0
        a, b, s, t, dvec, dist, xo = a[keep], b[keep], s[keep], t[keep], dvec[keep], dist[
            keep], xo[keep]
        normal = dvec / np.maximum(dist, 1e-300)[:, None]
        w = xo / 2.0
        cosang = np.abs(np.einsum("ij,ij->i", e[a], e[b]) / (le[a] * le[b]))
        q_line = math.cos(math.radians(law.angle_line_deg)) ** 2
        q_point = math.cos(math.radians(law.angle_point_deg)) ** 2
        u = np.clip((q_line - cosang**2) / (q_line - q_point), 0.0, 1.0)
        xi = u**3 * (10 - 15 * u + 6 * u * u)
        # Strongest contact per edge (both sides of each pair), then the opposite side.
        for edges, nrm in ((a, normal), (b, -normal)):
            order = np.argsort(w)
            for k in order:  # ascending, so the largest ends up stored
                j = edges[k]
                if w[k] >= w1[j]:
                    w1[j], n1[j], xi_e[j] = w[k], nrm[k], xi[k]
        for edges, nrm in ((a, normal), (b, -normal)):
            opp = np.einsum("ij,ij->i", nrm, n1[edges]) < -0.5
            for k in np.flatnonzero(opp):
                w2[edges[k]] = max(w2[edges[k]], w[k])
        va = np.where(s < 0.5, ev[a, 0], ev[a, 1])
        vb = np.where(t < 0.5, ev[b, 0], ev[b, 1])
        pair_list = np.c_[va, vb, 2.0 * w]
    # Edge -> vertex: the larger of the vertex's edges.
    to_vertex = m.vertex_max_of_edges
    stretch_v = m.vertex_mean_of_edges(stretch_e)
    dv = to_vertex(d0)
    w1v, w2v, xiv = to_vertex(w1), to_vertex(w2), to_vertex(xi_e)
    emod = np.array([m.rods[r].material.youngs_modulus for r in m.vertex_rod])
    f_line = law.k_line * emod * dv * (w1v / dv) ** law.p_line / emod  # f/E [m]
    if law.rigid:
        half = np.zeros(n)
        lc = np.zeros(n)
        p_mean = np.zeros(n)
        p_peak = np.zeros(n)
        area = 1.0 / stretch_v
    else:
        half = law.half_width(w1v, dv)
        lc = np.minimum(law.contact_fraction(w1v, dv) + law.contact_fraction(w2v, dv), 1.0)
        p_mean = np.where(half > 0, f_line / (2.0 * np.maximum(half, 1e-300)), 0.0)
        p_peak = (1 - xiv) * law.peak_pressure_line(w1v, dv) + xiv * law.peak_pressure_point(
            w1v, dv)
        area = law.area_factor(0.5 * (w1v + w2v), dv) / stretch_v
    force = f_line * emod
    weight_sum = None
    circles = None
    if isinstance(layer, SectionedLayer):
        if state is None:
            raise ValueError("the sectioned contact level's report needs the state (its "
                             "sections)")
        sec = layer.section_report(x, state.extra, state.frames,
                                   rest)
        half, lc, area = sec["half_width"], sec["contact_width_fraction"], sec["area_ratio"]
        p_mean, p_peak = sec["mean_pressure_over_E"], sec["peak_pressure_over_E"]
        force = sec["force_per_length"]
        weight_sum = sec["contact_weight_sum_mean"]
        circles = {k: sec[k] for k in CIRCLE_KEYS}
    return ContactReport(
        overlap=2.0 * w1v, overlap_opposite=2.0 * w2v,
        force_per_length=force, half_width=half, contact_width_fraction=lc,
        mean_pressure_over_E=p_mean, peak_pressure_over_E=p_peak, area_ratio=area,
        pairs=pair_list, weight_sum_mean=weight_sum, circles=circles)
