"""Two soft rods crossing at 90 degrees (barrier contact) against the rigid-cylinder
indent at the same per-rod approach: what the FEM says about the rod model's pair law,
which is calibrated on rigid counter-bodies and splits a pair's overlap evenly (and so
predicts the same force for both)."""

import math

import pytest

pytest.importorskip("felupe")
pytest.importorskip("ipctk")

SLOW = pytest.mark.slow  # the coarse scene's 4 levels and the rigid indent: about 3 min


@pytest.fixture(scope="module")
def small_crossing():
    """One level at w = 0.003 D0, coarse, with the rigid indent (about 16 s)."""
    from tightknot.fem import run_scene

    return run_scene("soft_crossing", mesh="coarse", max_approach_over_d0=0.006, steps=1)


def test_small_crossing_symmetry_and_balance(small_crossing):
    # the cheap check of the scene's construction: B is A turned about x = z, so both
    # rods must carry the same peak pressure and constriction (measured equal to 1e-12);
    # the force through the barrier balances; the rods touch but do not pass through;
    # the soft pair is stiffer than the rigid indent (2.18 here, where the coarse mesh
    # does not resolve the patch: the level is for the construction, not the ratio)
    step = small_crossing["steps"][0]
    assert step["w_over_d0"] == pytest.approx(0.003)
    assert step["peak_pressure_b_over_e"] == pytest.approx(step["peak_pressure_over_e"],
                                                           rel=1e-6)
    assert step["area_ratio_mid_b"] == pytest.approx(step["area_ratio_mid"], rel=1e-9)
    assert abs(step["force_balance_rel"]) < 1e-9
    assert 0.0 < step["min_gap_over_d0"] < small_crossing["parameters"]["dhat_over_d0"]
    ratio = small_crossing["comparison"]["relative_difference_soft_over_rigid"][0][
        "force_ratio_soft_over_rigid"]
    assert ratio > 1.3


@SLOW
def test_soft_crossing_is_stiffer_than_the_rigid_indent(soft_crossing_coarse):
    # measured soft/rigid force at w/D0 = 0.0094, 0.0375, 0.084, 0.15 (coarse): 1.60,
    # 1.58, 1.64, 1.79, where Hertz gives sqrt(2) = 1.41 and the rod model's even split
    # 1.0; the band [1.3, 2.0] says "well above the law's 1" without pinning the numbers
    # (medium: 1.56, 1.54 at the first two levels, docs/fem_nip.md)
    rows = soft_crossing_coarse["comparison"]["relative_difference_soft_over_rigid"]
    for row in rows:
        assert 1.3 < row["force_ratio_soft_over_rigid"] < 2.0
        assert row["hertz_ratio"] == pytest.approx(math.sqrt(2.0))


@SLOW
def test_patch_is_wider_by_about_sqrt2(soft_crossing_coarse):
    # Hertz: a = sqrt(2 R w) for two soft rods against sqrt(R w) on a rigid one; measured
    # soft/rigid semi-axes 1.35 to 1.55 from w = 0.0375 D0 on (the first level's patch
    # spans two to three nodes on the coarse mesh: 1.26 and 1.55)
    soft = soft_crossing_coarse["steps"]
    rigid = soft_crossing_coarse["comparison"]["rigid_steps"]
    for s, r in list(zip(soft, rigid, strict=True))[1:]:
        for key in ("semi_axis_axial_over_d0", "semi_axis_transverse_over_d0"):
            assert 1.2 < s[key] / r[key] < 1.7


@SLOW
def test_both_rods_see_the_same_contact(soft_crossing_coarse):
    # B is A turned about the line x = z, y = y_B/2: by that symmetry both rods carry the
    # same peak pressure and the same mid-section constriction (to the solver tolerance)
    dhat = soft_crossing_coarse["parameters"]["dhat_over_d0"]
    for step in soft_crossing_coarse["steps"]:
        assert step["peak_pressure_b_over_e"] == pytest.approx(step["peak_pressure_over_e"],
                                                               rel=1e-5)
        assert step["area_ratio_mid_b"] == pytest.approx(step["area_ratio_mid"], rel=1e-6)
        assert abs(step["force_balance_rel"]) < 1e-9
        assert 0.0 < step["min_gap_over_d0"] < dhat


@SLOW
def test_profile_along_the_rod(soft_crossing_coarse):
    last = soft_crossing_coarse["steps"][-1]
    profile = last["profile_a"]
    assert profile[0]["z_over_d0"] == 0.0
    assert profile[0]["area_ratio"] == pytest.approx(last["area_ratio_mid"], rel=1e-12)
    # the constriction and the contact width fall away from the crossing; beyond the
    # patch (a = 0.44 D0 along the rod) no contact is left
    lc = [row["contact_fraction"] for row in profile]
    assert all(b <= a + 1e-12 for a, b in zip(lc, lc[1:], strict=False))
    assert lc[0] > 0.2 and lc[-1] == 0.0
    assert profile[-1]["area_ratio"] > profile[0]["area_ratio"]
