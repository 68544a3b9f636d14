"""Laying a closed knot flat: rho(s), z(s) independent of the frame the data come in."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tightknot.knots import curves
from tightknot.knots.closed_measures import barycenter, closed_knot_profile, threefold_axis
from tightknot.knots.ideal import load_ideal_trefoil


@pytest.mark.parametrize("which", ["parametric", "ideal"])
def test_rotated_translated_trefoil_same_profile(which):
    pts = curves.trefoil(900, 0.01) if which == "parametric" else load_ideal_trefoil(0.0085)
    ref = closed_knot_profile(pts, 0.0085)
    for seed in range(3):
        rot = Rotation.random(random_state=seed).as_matrix()
        moved = pts @ rot.T + np.array([0.3, -2.0, 5.0]) * (seed + 1)
        got = closed_knot_profile(moved, 0.0085)
        # Rotation and translation are exact up to round-off of positions ~1e-15 * 5 m
        # offsets / 8.5 mm diameters: 1e-9 in units of D0.
        # Compare per vertex: a vertex sitting at s = +-L0/(2 D0) may wrap either way.
        per_ref = np.argsort(ref["order"])
        per_got = np.argsort(got["order"])
        period = 2 * np.max(np.abs(ref["s"]))
        ds = got["s"][per_got] - ref["s"][per_ref]
        np.testing.assert_allclose((ds + period / 2) % period - period / 2, 0, atol=1e-9)
        for key in ("rho", "z", "X_over_D0", "Y_over_D0"):
            np.testing.assert_allclose(got[key][per_got], ref[key][per_ref], atol=1e-9)
        np.testing.assert_allclose(got["axis"], rot @ ref["axis"], atol=1e-9)


def test_axis_of_parametric_trefoil_is_z():
    pts = curves.trefoil(600)
    axis, spreads = threefold_axis(pts)
    # The parametric curve is 3-fold symmetric about e_z exactly (sampled at 600 = 3 * 200).
    np.testing.assert_allclose(np.abs(axis), [0, 0, 1], atol=1e-12)
    assert spreads[2] / spreads[1] == pytest.approx(1.0, abs=1e-9)
    np.testing.assert_allclose(barycenter(pts), 0.0, atol=1e-12)


def test_z_sign_follows_mirror_and_reversal():
    pts = curves.trefoil(600)
    ref = closed_knot_profile(pts, 1.0)
    mirror = closed_knot_profile(pts * np.array([1, 1, -1.0]), 1.0)
    # The mirror image turns the same way about e_z but has every height flipped.
    np.testing.assert_allclose(mirror["z"], -ref["z"], atol=1e-9)
    np.testing.assert_allclose(mirror["rho"], ref["rho"], atol=1e-9)


def test_segments_and_origin():
    pts = curves.trefoil(600)
    prof = closed_knot_profile(pts, 1.0)
    period = prof["s"].max() - prof["s"].min()
    rho = prof["rho"]
    assert rho[np.argmin(np.abs(prof["s"]))] == pytest.approx(rho.max(), rel=1e-4)
    outer = np.array(prof["outer_segments_s"])
    inner = np.array(prof["inner_segments_s"])
    # Equally spaced by a third of the length, inner halfway between outer (D3 symmetry);
    # the resolution is one vertex spacing (period / 600), refined by a parabola.
    np.testing.assert_allclose(np.diff(outer), period / 3, atol=period / 600)
    np.testing.assert_allclose(np.sort(np.abs(inner))[:2], period / 6, atol=period / 600)
    for s_in in inner:
        assert np.interp(s_in, prof["s"], rho) < rho.mean()


def test_stretch_rescales_s():
    pts = curves.trefoil(600, 0.01)
    length = np.sum(np.linalg.norm(np.roll(pts, -1, 0) - pts, axis=1))
    prof = closed_knot_profile(pts, 0.001, rest_length=0.9 * length)
    # s = S / L * L0 / D0 spans L0 / D0 whatever the stretch (Johanns et al. 2021).
    assert prof["s"].max() - prof["s"].min() == pytest.approx(0.9 * length / 0.001, rel=1e-2)
