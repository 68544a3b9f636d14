"""Two U-shaped soft rods hooked and pulled apart (barrier contact, displacement control):
the construction's symmetry, the force balance, the profiles and the patch."""

import numpy as np
import pytest

pytest.importorskip("felupe")
pytest.importorskip("ipctk")


@pytest.fixture(scope="module")
def one_level(clasp_one_level):
    return clasp_one_level


def test_rotation_maps_a_onto_b():
    from tightknot.fem.scenes.clasp import rotate_to_b, u_centreline

    rng = np.random.default_rng(0)
    x = rng.standard_normal((5, 3))
    assert np.allclose(rotate_to_b(rotate_to_b(x)), x)  # a half turn
    rot = rotate_to_b(np.eye(3))
    assert np.linalg.det(rot) == pytest.approx(1.0)  # proper: hexahedra stay positive
    c, n_in = u_centreline(np.array([0.0, 0.5, 10.0]), 1.5, -1.0)
    assert np.allclose(c[0], [0.5, 0.0, 0.0])  # the apex
    assert np.allclose(n_in[0], [-1.0, 0.0, 0.0])  # inner side toward -x
    assert np.allclose(c[2, 1], 1.5) and np.allclose(n_in[2], [0.0, -1.0, 0.0])  # the leg


def test_force_balance_and_symmetry(one_level):
    # the clamps' pull equals the contact force through the barrier (statics: the
    # symmetry planes carry no x force), to the Newton tolerance; B is A turned by a
    # half turn, so both rods carry the same peak pressure and constriction
    step = one_level["steps"][0]
    assert step["force"] > 0.0
    assert abs(step["force_balance_rel"]) < 1e-6
    assert step["peak_pressure_b_over_e"] == pytest.approx(step["peak_pressure_over_e"],
                                                           rel=1e-5)
    assert step["area_ratio_apex_b"] == pytest.approx(step["area_ratio_apex"], rel=1e-6)
    assert 0.0 < step["min_gap_over_d0"] < one_level["parameters"]["dhat_over_d0"]


def test_profiles_and_patch(one_level):
    step = one_level["steps"][0]
    prof = step["profile_a"]
    assert len(prof) == one_level["mesh"]["layers"]
    assert prof[0]["contact_fraction"] > 0.0  # the apex is in contact
    assert prof[-1]["contact_fraction"] == 0.0  # the clamp is not
    assert step["area_ratio_apex"] < 1.0
    patch = step["patch_a"]
    assert max(patch["p_over_e"]) == pytest.approx(step["peak_pressure_over_e"])
    assert min(patch["phi_deg"]) >= 0.0


def test_bad_input_names_the_parameter():
    from tightknot.fem import run_scene

    for kwargs, name in (({"max_pull_over_d0": 3.0}, "max_pull_over_d0"),
                         ({"bend_radius_over_d0": 1.0}, "bend_radius_over_d0"),
                         ({"leg_length_over_d0": 0.5}, "leg_length_over_d0"),
                         ({"steps": 0}, "steps"), ({"mesh": "huge"}, "mesh")):
        with pytest.raises(ValueError, match=name):
            run_scene("clasp", **kwargs)
    with pytest.raises(ValueError, match="give max_pull_over_d0"):
        run_scene("clasp", max_approach_over_d0=0.3)


def test_cli_bad_input_is_one_line_exit_2(capsys):
    from tightknot.app.cli import main

    code = main(["fem", "clasp", "--pull", "5"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "max_pull_over_d0 must lie in (0, 2]" in err[0]


@pytest.mark.slow
def test_force_displacement_on_the_coarse_mesh():
    # six pulls to 1 D0 (about 2 minutes alone, more on shared cores): nothing before
    # the bends touch, then the force, the contact width and the constriction all grow
    # (measured F = 0.0031 ... 0.0531 E D0^2 from 0.5 D0 on, docs/fem_nip.md)
    from tightknot.fem import run_scene

    res = run_scene("clasp", mesh="coarse")
    steps = [s for s in res["steps"] if s["peak_pressure_over_e"] > 0.0]
    assert 2 <= len(steps) < len(res["steps"])  # the first pulls only close the gap
    for a, b in zip(steps, steps[1:], strict=False):
        assert b["force"] > a["force"]
        assert b["contact_fraction_max"] > a["contact_fraction_max"]
        assert b["area_ratio_apex"] < a["area_ratio_apex"]
        assert abs(b["force_balance_rel"]) < 1e-6
