"""A soft rod pulled around a soft rod (barrier contact, force control): statics, the
measured profiles and patch, and the comparison with the rigid wrap."""

import math

import pytest

pytest.importorskip("felupe")
pytest.importorskip("ipctk")


@pytest.fixture(scope="module")
def one_level(soft_wrap_one_level):
    return soft_wrap_one_level


def test_statics_and_gap(one_level):
    # frictionless: the contact force on A balances its two end loads, 2 T sin(theta),
    # exactly; the Newton residual (1e-8 of the reaction) leaves 1e-6 of room
    step = one_level["steps"][0]
    assert step["contact_force_total_over_2t_sin_theta"] == pytest.approx(1.0, abs=1e-6)
    assert 0.0 < step["min_gap_over_d0"] < one_level["parameters"]["dhat_over_d0"]
    assert step["tension_over_e_d0sq"] == pytest.approx(0.0069)


def test_both_rods_flatten_and_carry_the_patch(one_level):
    # both sections lose area at the contact (incompressible: the flattening and the
    # stretch), both carry a contact patch, and A's contact is widest at the middle
    step = one_level["steps"][0]
    assert step["area_ratio_mid"] < 1.0 and step["area_ratio_mid_b"] < 1.0
    prof_a, prof_b = step["profile_a"], step["profile_b"]
    assert prof_a[0]["contact_fraction"] > 0.0 and prof_b[0]["contact_fraction"] > 0.0
    assert prof_a[0]["contact_fraction"] == max(r["contact_fraction"] for r in prof_a)
    assert prof_a[-1]["contact_fraction"] == 0.0  # the far tail is free
    for patch in (step["patch_a"], step["patch_b"]):
        assert len(patch["p_over_e"]) == len(patch["s_over_d0"]) == len(patch["phi_deg"]) > 0
    # the patch map holds the peak: the loaded nodes include the most loaded one
    assert max(step["patch_a"]["p_over_e"]) == pytest.approx(step["peak_pressure_over_e"])
    assert max(step["patch_b"]["p_over_e"]) == pytest.approx(step["peak_pressure_b_over_e"])


def test_bad_input_names_the_parameter():
    from tightknot.fem import run_scene

    with pytest.raises(ValueError, match="max_tension_over_e_d0sq must lie in"):
        run_scene("soft_wrap", max_tension_over_e_d0sq=0.6)
    with pytest.raises(ValueError, match="wrap_angle_deg must lie in"):
        run_scene("soft_wrap", wrap_angle_deg=150.0)
    with pytest.raises(ValueError, match="dhat_over_d0 must lie in"):
        run_scene("soft_wrap", dhat_over_d0=0.1)
    with pytest.raises(ValueError, match="max_approach_over_d0 is not a parameter"):
        run_scene("soft_wrap", max_approach_over_d0=0.2)


@pytest.mark.slow
def test_soft_wrap_against_the_rigid_wrap():
    # six levels on the coarse mesh with the rigid wrap (about 10 minutes on 2 shared
    # cores); the measured ratios are in docs/fem_nip.md
    from tightknot.fem import run_scene

    res = run_scene("soft_wrap", mesh="coarse")
    for step, row in zip(res["steps"], res["comparison"]["ratios"], strict=True):
        assert step["contact_force_total_over_2t_sin_theta"] == pytest.approx(1.0, abs=1e-6)
        # statics fix the total force in both: the soft pair can only redistribute it
        assert math.isfinite(row["force_per_length_mid_nominal_over_e_d0_soft_over_rigid"])
