"""Wrap scene (rod under tension pulled around a rigid cylinder): statics, small-load
sanity, monotone constriction, mesh convergence."""

import json
import math

import pytest

pytest.importorskip("felupe")

from tightknot.fem import run_scene  # noqa: E402


def test_total_contact_force_is_statics(wrap_coarse):
    # the frictionless cylinder balances both end forces: sum of contact forces =
    # 2 T sin(theta) exactly; the Newton tolerance (1e-8 of the reactions) bounds the rest.
    # A lost symmetry factor (x2 or x4) or a wrong force component would be off by 30 %+.
    theta = math.radians(wrap_coarse["parameters"]["wrap_angle_deg"]) / 2
    for step in wrap_coarse["steps"]:
        assert step["contact_force_total"] == pytest.approx(
            2 * step["tension"] * math.sin(theta), rel=1e-6)


def test_small_load_sanity(wrap_coarse):
    first = wrap_coarse["steps"][0]
    # T = 0.0069 E D0^2 (axial strain ~ 0.9 %): measured approach 0.036 D0 (mostly the
    # tails bending away: the rod is not yet wrapped, kappa D0 = 0.50), area 0.979
    assert first["tension_over_e_d0sq"] == pytest.approx(0.25 / 36)
    assert 0.0 < first["overlap_over_d0"] < 0.06
    assert 0.96 < first["area_ratio_mid"] < 1.0
    assert 0.0 < first["kappa_d0_mid"] < 1.0
    assert first["axial_stretch_mid"] == pytest.approx(1.0, abs=0.03)
    for step in wrap_coarse["steps"]:
        # K = 5000 mu: |dV/V| <= p/K < 0.8 E / (5000 E / 3) = 4.8e-4
        assert abs(step["volume_ratio"] - 1.0) < 5e-4


def test_constriction_grows_with_tension(wrap_coarse):
    steps = wrap_coarse["steps"]
    for key, sign in (("area_ratio_mid", -1), ("height_over_d0", -1), ("flattening", 1),
                      ("overlap_over_d0", 1), ("kappa_d0_mid", 1), ("peak_pressure_over_e", 1),
                      ("force_per_length_mid", 1)):
        values = [s[key] for s in steps]
        assert all(sign * (b - a) > 0 for a, b in zip(values, values[1:], strict=False)), key
    last = steps[-1]
    # T = 0.25 E D0^2: measured A/A0 = 0.572, flattening 0.476, kappa D0 = 1.32 (coarse);
    # the section constricts far more than the stretch alone (1/lambda = 0.584) would say
    assert 0.5 < last["area_ratio_mid"] < 0.65
    assert last["area_ratio_mid"] < last["area_ratio_stretch_only"]
    assert 1.1 < last["kappa_d0_mid"] < 1.5


def test_wrap_json(wrap_coarse):
    result = json.loads(json.dumps(wrap_coarse, allow_nan=False))
    assert result["scene"] == "wrap"
    for key in ("mesh", "parameters", "steps", "closed_form", "hertz", "mesh_convergence",
                "wall_time_s"):
        assert key in result
    assert result["wall_time_s"] > 0.0


@pytest.mark.slow
def test_wrap_mesh_convergence():
    result = run_scene("wrap", mesh="coarse", convergence=True)
    meshes = result["mesh_convergence"]["meshes"]
    assert [m["mesh"] for m in meshes] == ["coarse", "medium", "fine"]
    assert meshes[0]["elements"] < meshes[1]["elements"] < meshes[2]["elements"]
    for key in ("area_ratio_mid", "overlap_over_d0", "kappa_d0_mid"):
        diff = [abs(m["relative_difference_to_finest"][key]) for m in meshes]
        assert diff[0] > diff[1], key
