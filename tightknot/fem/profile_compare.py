"""Profiles along a rod compared: the FEM's node layers against the rod model's vertices.

Issue 18 asks for the contact width fraction L_c within 0.1 and A/A0 within 5 points *along
the contact*, not only at the middle section, and for the FEM's and the rod model's profiles
side by side where the nip does not reach what the FEM shows. Both sides report a profile
per rod as a list of rows (``s_over_d0``: rest arc length from the middle of the wrap or the
clasp's apex [D0], or ``z_over_d0`` along a straight rod; ``area_ratio`` A/A0;
``contact_fraction`` L_c; ``peak_pressure_over_e``): the FEM per node layer
(:meth:`tightknot.fem.scenes._sections.RodSections.profile`), the rod
model per vertex (:func:`tightknot.fem.rod_model_soft._profile`) or, at the sectioned level,
per Gauss circle at the circle's own place (:func:`circle_profile`: a vertex's value is the
largest of its edges' circles, which reach 0.79 of an edge from it, so that a vertex
profile carries a contact's end outward by up to that much).

:func:`along_contact` reads the second profile, linearly interpolated in s, at each layer
of the first: the rod model against the FEM, or a coarser FEM mesh against the compared one
(the FEM's own spread, with the same measure). The contact is every layer where either
profile has L_c > 0, so a contact that one side spreads further than the other counts
against it at the layers it adds. The FEM counts a node as loaded above 1 % of the rod's
peak pressure (``tightknot.fem.scenes._pair.LOADED_FRACTION``); the sectioned level counts
a boundary sample that penetrates its partner, the compliant level reads its law's contact
width. Near the contact's ends the two sides therefore differ by that threshold, a small
part of the peak pressure.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: The profile rows' keys compared (:func:`along_contact`).
AREA_KEY = "area_ratio"
WIDTH_KEY = "contact_fraction"
PRESSURE_KEY = "peak_pressure_over_e"


def arc_length(row: dict[str, float]) -> float:
    """A row's rest arc length [D0]: ``s_over_d0``, or ``z_over_d0`` along a straight rod
    (the FEM's soft crossing)."""
    return row["s_over_d0"] if "s_over_d0" in row else row["z_over_d0"]


def circle_profile(circles: dict[str, np.ndarray], vertices: np.ndarray,
                   s_rest: np.ndarray, diameter: float) -> list[dict[str, float]]:
    """The sectioned level's profile at the Gauss circles of the edges that join
    consecutive ``vertices`` of one rod (rest arc length ``s_rest`` [m] of each), from the
    per-circle outputs ``circles`` of
    :meth:`~tightknot.contact.sectioned.SectionedLayer.section_report`
    (``circle_contact_width_fraction``, ``circle_peak_pressure_over_E``,
    ``edge_area_ratio``, ``circle_u``, ``edge_vertex``): a row per circle at its rest arc
    length [D0], in the order of ``vertices``."""
    ev = np.asarray(circles["edge_vertex"])
    edge_of = {(int(a), int(b)): e for e, (a, b) in enumerate(ev)}
    u_first = np.asarray(circles["circle_u"], dtype=float)
    rows = []
    for (va, sa), (vb, sb) in zip(zip(vertices[:-1], s_rest[:-1], strict=True),
                                  zip(vertices[1:], s_rest[1:], strict=True), strict=True):
        e = edge_of.get((int(va), int(vb)))
        us, order = u_first, np.arange(u_first.size)
        if e is None:  # the edge runs from vb to va: its circles from va's end first
            e = edge_of.get((int(vb), int(va)))
            us, order = 1.0 - us[::-1], order[::-1]
        if e is None:
            raise ValueError(f"vertices {int(va)} and {int(vb)} share no edge")
        for u, g in zip(us, order, strict=True):
            rows.append({"s_over_d0": float(sa + u * (sb - sa)) / diameter,
                         AREA_KEY: float(circles["edge_area_ratio"][e]),
                         WIDTH_KEY: float(circles["circle_contact_width_fraction"][e, g]),
                         PRESSURE_KEY: float(circles["circle_peak_pressure_over_E"][e, g])})
    return rows


def _columns(profile: list[dict[str, float]]) -> dict[str, np.ndarray]:
    """A profile's rows as columns, sorted by s."""
    s = np.array([arc_length(r) for r in profile], dtype=float)
    order = np.argsort(s, kind="stable")
    out = {k: np.array([profile[i][k] for i in order], dtype=float)
           for k in (AREA_KEY, WIDTH_KEY, PRESSURE_KEY)}
    out["s_over_d0"] = s[order]
    return out


def _loaded_end(col: dict[str, np.ndarray]) -> float:
    """Rest arc length of a profile's last loaded row [D0] (0 where none is loaded)."""
    s = col["s_over_d0"][col[WIDTH_KEY] > 0.0]
    return float(s.max()) if s.size else 0.0


def along_contact(reference: list[dict[str, float]], other: list[dict[str, float]]
                  ) -> dict[str, Any] | None:
    """``other``'s profile against ``reference``'s along their contact (module docstring).

    At each row of ``reference`` within ``other``'s range of s, ``other``'s A/A0, L_c and
    p/E are interpolated linearly in s; the contact is the rows where either L_c > 0.
    Returns None where neither is loaded; else ``rows`` (the compared rows: ``s_over_d0``,
    both sides' values and ``width_fraction`` = other - reference L_c, ``area_points`` =
    other - reference A/A0), the largest absolute differences along the contact
    (``width_fraction_max``, ``area_points_max``, each with the signed value and its
    ``..._at_s_over_d0``), both sides' loaded ends (``contact_end_*_over_d0``), largest
    L_c and smallest A/A0 along the contact."""
    ref, oth = _columns(reference), _columns(other)
    if ref["s_over_d0"].size == 0 or oth["s_over_d0"].size == 0:
        return None
    s = ref["s_over_d0"]
    inside = (s >= oth["s_over_d0"][0]) & (s <= oth["s_over_d0"][-1])
    s = s[inside]
    mine = {k: ref[k][inside] for k in (AREA_KEY, WIDTH_KEY, PRESSURE_KEY)}
    theirs = {k: np.interp(s, oth["s_over_d0"], oth[k])
              for k in (AREA_KEY, WIDTH_KEY, PRESSURE_KEY)}
    contact = (mine[WIDTH_KEY] > 0.0) | (theirs[WIDTH_KEY] > 0.0)
    if not contact.any():
        return None
    sc = s[contact]
    mine = {k: v[contact] for k, v in mine.items()}
    theirs = {k: v[contact] for k, v in theirs.items()}
    d_width = theirs[WIDTH_KEY] - mine[WIDTH_KEY]
    d_area = theirs[AREA_KEY] - mine[AREA_KEY]
    iw, ia = int(np.argmax(np.abs(d_width))), int(np.argmax(np.abs(d_area)))
    rows = [{"s_over_d0": float(sc[j]),
             "reference_area_ratio": float(mine[AREA_KEY][j]),
             "other_area_ratio": float(theirs[AREA_KEY][j]),
             "reference_contact_fraction": float(mine[WIDTH_KEY][j]),
             "other_contact_fraction": float(theirs[WIDTH_KEY][j]),
             "reference_peak_pressure_over_e": float(mine[PRESSURE_KEY][j]),
             "other_peak_pressure_over_e": float(theirs[PRESSURE_KEY][j]),
             "width_fraction": float(d_width[j]), "area_points": float(d_area[j])}
            for j in range(sc.size)]
    return {
        "layers": int(sc.size),
        "width_fraction_max": float(abs(d_width[iw])),
        "width_fraction_signed": float(d_width[iw]),
        "width_fraction_at_s_over_d0": float(sc[iw]),
        "area_points_max": float(abs(d_area[ia])),
        "area_points_signed": float(d_area[ia]),
        "area_points_at_s_over_d0": float(sc[ia]),
        "contact_end_reference_over_d0": _loaded_end(ref),
        "contact_end_other_over_d0": _loaded_end(oth),
        "reference_width_fraction_peak": float(mine[WIDTH_KEY].max()),
        "other_width_fraction_peak": float(theirs[WIDTH_KEY].max()),
        "reference_area_ratio_min": float(mine[AREA_KEY].min()),
        "other_area_ratio_min": float(theirs[AREA_KEY].min()),
        "rows": rows,
    }


def spread_summary(comparison: dict[str, Any] | None) -> dict[str, float] | None:
    """The largest differences of a FEM mesh against the next coarser one along the
    contact (:func:`along_contact`'s ``width_fraction_max`` and ``area_points_max``), the
    FEM's own spread beside a profile comparison; None without one."""
    if comparison is None:
        return None
    return {"width_fraction_max": comparison["width_fraction_max"],
            "area_points_max": comparison["area_points_max"]}
