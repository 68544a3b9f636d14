"""Squeeze scene: plane-strain Hertz at small load, incompressibility, 3D = plane strain
with plane ends, mesh convergence."""

import json

import pytest

pytest.importorskip("felupe")

from tightknot.fem import run_scene  # noqa: E402

DOCUMENTED_STEP_KEYS = {
    "approach_over_d0", "w_over_d0", "force_per_length", "force_per_length_over_e_d0",
    "half_width_over_d0", "contact_fraction_side", "peak_pressure_over_e",
    "mean_pressure_over_e", "area_ratio", "volume_ratio",
}


def _hertz_row(result, w_hat):
    rows = result["hertz"]["steps"]
    return min(rows, key=lambda r: abs(r["w_over_d0"] - w_hat))


def test_plane_strain_force_matches_hertz_line_contact(squeeze_plane_strain_convergence):
    # At w/D0 = 0.0094 (b/R = 0.11) the FEM force per length is within 0.2 % (coarse),
    # 0.3 % (medium), 0.4 % (fine) of the plane-strain Hertz relation (Johnson 1985
    # sec. 5.6); the residual is Hertz's own small-b/R and small-strain approximation.
    # 1 % leaves room for that, while a wrong E* (two elastic bodies) or a missing factor
    # 2 for the symmetry half would be off by 30 % or more.
    row = _hertz_row(squeeze_plane_strain_convergence, 0.0094)
    assert row["w_over_d0"] == pytest.approx(0.009375)
    assert abs(row["force_rel_error"]) < 0.01
    # peak pressure at the FEM force, eq. 4.44: measured -0.9 % coarse, 0.0 % fine; the
    # nodal pressure of the coarse mesh (b spans 2 to 3 elements) limits it: 3 %
    assert abs(row["peak_pressure_rel_error"]) < 0.03
    # half-width: +1.2 % coarse, +0.1 % fine (edge extrapolation between nodes): 5 %
    assert abs(row["half_width_rel_error"]) < 0.05


def test_incompressibility(squeeze_plane_strain_convergence):
    # K = 5000 mu: volume change |dV/V| <= p/K <= 0.6 E / (5000 E/3) = 3.6e-4 for the
    # pressures reached (p_max < 0.6 E); area is conserved in plane strain up to that.
    for step in squeeze_plane_strain_convergence["steps"]:
        assert abs(step["volume_ratio"] - 1.0) < 4e-4
        assert abs(step["area_ratio"] - 1.0) < 4e-4


def test_force_grows_with_approach(squeeze_plane_strain_convergence):
    steps = squeeze_plane_strain_convergence["steps"]
    forces = [s["force_per_length"] for s in steps]
    assert all(b > a for a, b in zip(forces, forces[1:], strict=False))
    assert steps[-1]["approach_over_d0"] == pytest.approx(0.3)


def test_mesh_convergence_table(squeeze_plane_strain_convergence):
    table = squeeze_plane_strain_convergence["mesh_convergence"]
    meshes = table["meshes"]
    assert [m["mesh"] for m in meshes] == ["coarse", "medium", "fine"]
    assert meshes[0]["elements"] < meshes[1]["elements"] < meshes[2]["elements"]
    diff = [abs(m["relative_difference_to_finest"]["force_per_length_over_e_d0"])
            for m in meshes]
    # measured: 0.15 % (coarse, 192 quads) and 0.08 % (medium, 768) at w/D0 = 0.15;
    # the force must converge monotonically and the coarsest be within 0.5 %
    assert diff[0] > diff[1] > 0.0
    assert diff[0] < 0.005


def test_result_is_json_with_documented_keys(squeeze_plane_strain_convergence):
    result = squeeze_plane_strain_convergence
    text = json.dumps(result, allow_nan=False)  # raises on NaN or non-JSON types
    assert json.loads(text)["scene"] == "squeeze"
    for key in ("scene", "mesh", "parameters", "steps", "hertz", "mesh_convergence",
                "wall_time_s"):
        assert key in result
    assert DOCUMENTED_STEP_KEYS <= set(result["steps"][0])
    assert result["wall_time_s"] > 0.0


def test_3d_plane_ends_reproduce_plane_strain():
    # frictionless plane ends (u_z = 0) admit exactly the plane-strain solution, and the
    # coarse 3D section mesh is the coarse plane-strain mesh: same numbers up to the
    # Newton tolerance (1e-8 relative residual), so 1e-5 is generous
    a = run_scene("squeeze", mesh="coarse", steps=4, model="3d", ends="plane",
                  convergence=False)
    b = run_scene("squeeze", mesh="coarse", steps=4, model="plane_strain", convergence=False)
    for sa, sb in zip(a["steps"], b["steps"], strict=True):
        assert sa["force_per_length"] == pytest.approx(sb["force_per_length"], rel=1e-5)
        assert sa["half_width_over_d0"] == pytest.approx(sb["half_width_over_d0"], rel=1e-5)
