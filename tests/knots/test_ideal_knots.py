"""The shipped ideal knots 3_1, 4_1, 5_1, 6_1, 8_19 (data/README.md): bytes, type, L/D, and
their use as the catalogue's ideal lengths and as start shapes."""

import hashlib
from importlib import resources

import numpy as np
import pytest

from tightknot.knots import catalogue, curves, scenes
from tightknot.knots.contact_map import polygonal_thickness
from tightknot.knots.ideal import IDEAL_KNOTS, has_ideal, load_ideal
from tightknot.knots.topology import knot_type

#: Upstream sha256s of designbynumbers/ropelength-minimizing-knots @ 0d78454, copied from
#: the mirror's MANIFEST.json (Njakasoa/tight-knots-ropelength): written out here so that a
#: change of the table in ideal.py cannot pass unseen.
MANIFEST = {
    "3_1": "e649e6d41a9d0a76bf6be1a93c6eed483ac3c949b6677f3f59520d0e958e8c3c",
    "4_1": "099996e1d47c9879be3fe526bf22971e4127f603b6261cd34da036d77c9be7e4",
    "5_1": "d88ab5312607cdb6493ac4941211f7c90a70b2a49edd6a5e7bc65d40af6eea94",
    "6_1": "a09e80263d9fdf03c395d9a584cea165799d977aa20319baab7b2aeb9c1ae52d",
    "8_19": "764bc2fe9a6cb186dc7aaeaf01cd2ab78a0aeb87421e47e5cb0f578f42c1a88b",
}


@pytest.mark.parametrize("name", list(MANIFEST))
def test_shipped_file_is_the_upstream_one_and_attributed(name):
    knot = IDEAL_KNOTS[name]
    raw = resources.files("tightknot.knots").joinpath("data", knot.file).read_bytes()
    assert hashlib.sha256(raw).hexdigest() == knot.sha256 == MANIFEST[name]
    readme = resources.files("tightknot.knots").joinpath("data", "README.md").read_text()
    assert knot.file in readme and knot.sha256 in readme and "CC0" in readme


@pytest.mark.parametrize("name", list(MANIFEST))
def test_ideal_has_its_type_and_its_measured_length(name):
    pts = load_ideal(name, 2.0)
    assert knot_type(pts) == name
    # Scaled to the tube diameter asked for: polygonal thickness r = D/2.
    assert polygonal_thickness(pts, closed=True) == pytest.approx(1.0, rel=1e-12)
    length = float(np.linalg.norm(np.roll(pts, -1, axis=0) - pts, axis=1).sum())
    # The stored L/D is this measurement rounded to 4 decimals.
    assert length / 2.0 == pytest.approx(IDEAL_KNOTS[name].l_over_d, abs=5e-5)
    # Known (not estimated) in the catalogue, from the same measurement.
    assert catalogue.ideal_l_over_d(name) == (IDEAL_KNOTS[name].l_over_d, True)


def test_a_damaged_or_unknown_ideal_is_refused():
    assert has_ideal("5_1") and not has_ideal("5_2")
    with pytest.raises(ValueError, match="shipped: 3_1, 4_1, 5_1, 6_1, 8_19"):
        load_ideal("5_2")


@pytest.mark.parametrize("name", ["4_1", "5_1"])
def test_ideal_start_shape_starts_tight_and_fits_the_tube(name):
    d0 = scenes.STUDY_DIAMETER
    ratio = scenes.default_l0_over_d0(name)
    parametric = scenes.closed_knot(name, nodes=200)
    ideal = scenes.closed_knot(name, nodes=200, start_shape="ideal")
    assert ideal.info["start_shape"] == "ideal" and ideal.knot_type == name
    assert ideal.rest_length == parametric.rest_length == pytest.approx(ratio * d0)
    # Started in the tight shape: a few per cent above L0 (the tube's 2 % margin and the
    # resampled polygon's sharper corners), where the parametric curve starts far looser.
    assert 1.0 <= ideal.start_length_ratio < 1.06 < parametric.start_length_ratio
    curves.check_no_overlap(ideal.state.x, d0, True)
    assert knot_type(ideal.state.x) == name
    # The rebuilt scene (mesh continuation) keeps the ideal start.
    assert ideal.rebuild(100).info["start_shape"] == "ideal"


def test_default_parametric_start_is_unchanged():
    # The start shape defaults to the family's curve: the study's trefoil as before.
    a = scenes.closed_knot("3_1", nodes=60)
    b = scenes.closed_trefoil(nodes=60)
    assert np.array_equal(a.state.x, b.state.x) and "start_shape" not in a.info
