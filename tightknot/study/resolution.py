"""What a run's vertex count costs in accuracy, from the trade-off study.

The numbers are those of ``tightknot bench tradeoff`` as the README quotes them ("Speed
versus accuracy"): the closed trefoil's curvature kappa*D0 at 100 vertices is within 0.0015
(RMS) of the 800-vertex run; the tight open trefoil's (L0 = 125 mm, 6.08 N) is off by 0.16
to 0.28 at 100 to 200 vertices, and 400 vertices are recommended. Nothing else was measured,
so other vertex counts get no number, only the nearest measured one.
"""

from __future__ import annotations

from typing import Any

#: Where the numbers come from.
SOURCE = "README 'Speed versus accuracy' (tightknot bench tradeoff)"
#: Recommended vertex counts of the trade-off study.
RECOMMENDED_NODES = {"closed": 100, "open": 400}
#: The closed trefoil at the recommended 100 vertices: kappa*D0 RMS error against 800.
CLOSED_KAPPA_RMS_AT_100 = 0.0015
#: The tight open trefoil at 100 to 200 vertices: kappa*D0 error against the finest run.
OPEN_KAPPA_ERROR_100_200 = (0.16, 0.28)


def resolution_note(closed: bool, nodes: int) -> dict[str, Any]:
    """The expected curvature error of a knot of ``nodes`` vertices: ``nodes``,
    ``recommended_nodes``, ``expected_kappa_D0_error`` (text, None where the study has no
    number), ``source`` and ``warning`` (None when the count is at least the recommended
    one)."""
    kind = "closed" if closed else "open"
    rec = RECOMMENDED_NODES[kind]
    out: dict[str, Any] = {"nodes": nodes, "recommended_nodes": rec, "source": SOURCE,
                           "expected_kappa_D0_error": None, "warning": None}
    if closed:
        if nodes >= rec:
            out["expected_kappa_D0_error"] = (f"within {CLOSED_KAPPA_RMS_AT_100:g} RMS (the "
                                              "closed trefoil at 100 vertices against 800)")
        else:
            out["warning"] = (f"{nodes} vertices, fewer than the {rec} the trade-off study "
                              "recommends for a closed knot; its error there was not "
                              f"measured ({SOURCE})")
        return out
    lo, hi = OPEN_KAPPA_ERROR_100_200
    if nodes >= rec:
        out["expected_kappa_D0_error"] = ("within 0.018 of the 400-vertex default-tolerance "
                                          "run (convergence in the vertex count not shown)")
        return out
    if 100 <= nodes <= 200:
        out["expected_kappa_D0_error"] = (f"{lo:g} to {hi:g} (the tight open trefoil at 100 "
                                          "to 200 vertices)")
        what = f"its curvature kappa*D0 is expected off by {lo:g} to {hi:g}"
    else:
        what = (f"its curvature error was not measured at this count ({lo:g} to {hi:g} at "
                "100 to 200 vertices)")
    out["warning"] = (f"{nodes} vertices, fewer than the {rec} the trade-off study recommends "
                      f"for an open knot: {what} ({SOURCE})")
    return out
