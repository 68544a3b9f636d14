"""The sectioned level's wrap under its two thinnings (rod model only, the FEM cross-check's
wrap scene at its lightest tension, 12 edges per D0): the traction of a frictionless
contact is across the rod, so an axial part of a vertex's contact force is the sections'
pull on their own edges' stretch, a force pair per edge (docs/sectioned_level.md,
"Resolution")."""

import pytest

from tightknot.contact.sectioned import SectionSettings
from tightknot.fem.material import ROD_DIAMETER, YOUNGS_MODULUS
from tightknot.fem.rod_model import indent_scene
from tightknot.fem.rod_sectioned import rod_wrap_sectioned

LIGHTEST = 0.0069 * YOUNGS_MODULUS * ROD_DIAMETER**2  # [N], the cross-check's first tension


def _lightest(thinning: str) -> dict:
    out = rod_wrap_sectioned([LIGHTEST], section=SectionSettings(thinning=thinning))
    (row,) = out["steps"]
    assert row["converged"]
    return row


def test_edge_thinning_pulls_the_pressed_edges_apart_and_rod_thinning_does_not() -> None:
    edge, rod = _lightest("edge"), _lightest("rod")
    # measured 2.32 (edge) and 0.09 (rod; 0.09 also with no thinning at all, the rest
    # being the sections' couples): the edge thinning's pull is the larger part
    assert edge["contact_axial_over_across_mid"] > 1.0
    assert rod["contact_axial_over_across_mid"] < 0.2
    # the window's vector sum holds nearly the whole contact force here (2 T sin 45 deg,
    # fixed by equilibrium): the two thinnings agree on it (measured 2.3 % apart)
    assert rod["force_per_length_mid_window_over_e_d0"] == pytest.approx(
        edge["force_per_length_mid_window_over_e_d0"], rel=0.05)


@pytest.mark.parametrize("bad", [3, 12.5, True])
def test_a_bad_rod_resolution_is_refused(bad: object) -> None:
    with pytest.raises(ValueError, match="edges_per_d0"):
        indent_scene(ROD_DIAMETER, YOUNGS_MODULUS, 3.0, edges_per_d0=bad)
