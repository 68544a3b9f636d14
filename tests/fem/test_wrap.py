"""Wrap scene (rod under tension pulled around a rigid cylinder): statics, small-load
sanity, monotone constriction, mesh convergence."""

import json
import math

import numpy as np
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


def test_nominal_axis_of_a_circle():
    from tightknot.fem.scenes.wrap import nominal_axis
    from tightknot.knots.curvature import bergou_curvature

    # far fibre on a circle of radius rho + r about (y, z) = (1, 0): the nominal axis is
    # the concentric circle of radius rho (exactly for equal spacing, as the refined
    # layers have: the central-difference chord is then normal to the radius)
    rho, r = 0.7, 0.4
    phi = np.linspace(0.0, 0.8, 5)
    far = np.column_stack([1.0 - (rho + r) * np.cos(phi), (rho + r) * np.sin(phi)])
    axis = nominal_axis(far, np.full(len(phi), r))
    # the last point's tangent is one-sided (not used at the middle): 1e-2
    assert np.hypot(axis[:-1, 0] - 1.0, axis[:-1, 1]) == pytest.approx(rho, rel=1e-9)
    assert np.hypot(axis[-1, 0] - 1.0, axis[-1, 1]) == pytest.approx(rho, rel=1e-2)
    pts = np.column_stack([np.zeros(3), axis[:3]])
    sym = np.vstack([pts[1:][::-1] * [1.0, 1.0, -1.0], pts])
    # Bergou curvature of a chord polygon of a circle, turning angle a per vertex:
    # 2 tan(a/2) / (2 rho sin(a/2)) = 1 / (rho cos(a/2))
    expected = 1.0 / (rho * math.cos(0.5 * (phi[1] - phi[0])))
    assert bergou_curvature(sym, closed=False)[2] == pytest.approx(expected, rel=1e-9)


def test_flattening_bends_the_centroid_line(wrap_coarse):
    for step in wrap_coarse["steps"]:
        # the far fibre plus the stretched radius lies nearer the cylinder than the
        # centroid (the flattened near side shifts the centroid away): measured 0.006 to
        # 0.083 D0 more approach, curvature 0.20 to 0.34 lower in kappa D0
        assert step["approach_nominal_over_d0"] > step["approach_over_d0"]
        assert step["kappa_d0_mid_nominal"] < step["kappa_d0_mid"]
    first = wrap_coarse["steps"][0]
    # T = 0.0069 E D0^2: the load is concentrated within 0.22 D0 of the middle; the
    # centroid line's kappa D0 = 0.505 is mostly the flattening, the nominal axis's 0.18
    assert first["kappa_d0_mid_nominal"] < 0.5 * first["kappa_d0_mid"]


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


def test_profile_along_the_rod(wrap_coarse):
    # A/A0, L_c and p/E per node layer (the soft scenes' profile, judged along the contact
    # by the sectioned cross-check): the middle layer's area is the one reported there, and
    # the contact is centred on the middle and ends within the rod
    for st in wrap_coarse["steps"]:
        prof = st["profile_a"]
        assert prof[0]["s_over_d0"] == 0.0
        assert prof[0]["area_ratio"] == pytest.approx(st["area_ratio_mid"], rel=1e-12)
        lc = np.array([r["contact_fraction"] for r in prof])
        assert np.all((lc >= 0.0) & (lc <= 1.0)) and lc[0] > 0.0 and lc[-1] == 0.0
        assert prof[0]["peak_pressure_over_e"] > 0.0
