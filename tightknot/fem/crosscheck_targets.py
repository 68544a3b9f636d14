"""The cross-check's targets and the range where they apply (one definition for the rows
of :mod:`tightknot.fem.crosscheck` and :mod:`tightknot.fem.crosscheck_soft`)."""

from __future__ import annotations

APPROACH_LIMIT: float = 0.25
"""Largest approach over D0 at which the targets apply (the issue's range)."""

TARGETS: dict[str, float] = {
    "force_rel": 0.10,
    "area_points": 0.05,
    "curvature_rel": 0.10,
    "width_fraction": 0.10,
}
"""Targets: relative force and curvature differences, area difference in points of A/A0
(absolute), and (sectioned level) the mid section's contact width fraction L_c (absolute).
"""
