"""Definitions of overlap used by the contact law, and how a pair overlap is split.

Pair overlap (rod model). Two centerline points i, j at distance d with (deformed)
section radii r_i, r_j overlap by

    delta = r_i + r_j - d            [m]   (in contact when delta > 0).

Per-side approach (FEM calibration). The law is calibrated PER SIDE: w [m] is the
reduction of the distance from the section centroid to the contact plane on one side
(w_hat = w / D0). In the FEM scenes:

- ``squeeze`` (plates): the plates move by w each; the centroid of the section stays at
  the symmetry plane y = 0, so w is the plate displacement and the total diameter
  reduction is Delta = 2 w. Two identical rods pressed together have w_i = w_j = delta/2,
  because their common mid-plane acts as a rigid frictionless plane by symmetry.
- ``indent`` (crossing rigid cylinders): each cylinder moves by w toward the rod axis; the
  centroid of the rod's mid cross-section (z = 0) stays on the axis by symmetry, so w is
  the indenter displacement. Two identical crossing strands pressed together: again
  w_i = w_j = delta/2 (the contact plane between them is a symmetry plane only for
  identical strands; for a rigid-on-elastic calibration this is the standard
  per-body split).
- In both, w includes the whole section's flattening (not only the local Hertz
  indentation): it is measured from the section centroid, exactly like the rod model's
  r_i - (distance from centerline point i to the contact point).

Different radii. With per-side laws f_i(w_i) (force per unit length for line contact,
force for point contact), the pair force f solves f_i(w_i) = f_j(w_j) = f with
w_i + w_j = delta (two springs in series, each with its own rod's law).
"""

from __future__ import annotations

from collections.abc import Callable

from scipy.optimize import brentq


def pair_overlap(r_i: float, r_j: float, distance: float) -> float:
    """Pair overlap delta = r_i + r_j - d [m] (positive in contact)."""
    return r_i + r_j - distance


def split_overlap_power(delta: float, d_i: float, d_j: float, exponent: float,
                        length_power: int) -> tuple[float, float]:
    """Split delta [m] into per-side approaches (w_i, w_j) [m] for power laws.

    Per-side law f = k E D^length_power (w/D)^exponent with the same k, E for both rods
    (``length_power`` 1: line contact, force per length; 2: point contact, force). Equal
    forces give D_i^(m - p) w_i^p = D_j^(m - p) w_j^p, hence
    w_i / w_j = (D_j / D_i)^((m - p) / p) with m = length_power, p = exponent.
    """
    if delta <= 0.0:
        return 0.0, 0.0
    ratio = (d_j / d_i) ** ((length_power - exponent) / exponent)  # w_i / w_j
    w_j = delta / (1.0 + ratio)
    return delta - w_j, w_j


def split_overlap(delta: float, force_i: Callable[[float], float],
                  force_j: Callable[[float], float]) -> tuple[float, float, float]:
    """Split delta [m] for general increasing per-side laws; return (w_i, w_j, f).

    Solves force_i(w_i) = force_j(delta - w_i) by bracketing on [0, delta].
    """
    if delta <= 0.0:
        return 0.0, 0.0, 0.0
    w_i = brentq(lambda w: force_i(w) - force_j(delta - w), 0.0, delta, xtol=1e-15 * delta)
    return w_i, delta - w_i, force_i(w_i)
