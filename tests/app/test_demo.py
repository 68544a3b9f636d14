"""The demo ties both trefoils and writes its summary, figures and a readable .rrd."""

import json

import numpy as np

from tightknot.viz.rrd_read import entity_paths, last_points3d, scalar_series, steps


def test_demo_outputs(tmp_path) -> None:
    from tightknot.app.demo import run_demo

    summary = run_demo(tmp_path)
    assert summary["passed"]
    closed = summary["knots"]["closed_trefoil"]
    loose = summary["knots"]["open_185mm"]
    tight = summary["knots"]["open_125mm"]
    for k in (closed, loose, tight):
        assert k["knot_type"] == "3_1" and k["alexander_at_minus1"] == 3
        # Squeezed sections, never passed through (hard limit 0.05 D0).
        assert 0.5 < k["min_gap_over_D0"] < 1.0
    # physics.md sec. 3: the closed elastic knot stretches a few percent and its L/D ends
    # well above the ideal 16.37 (measured 7.5 %, 18.3 at 100 vertices).
    assert 1.01 < closed["stretch"] < 1.2 and closed["L_over_D"] > 16.37
    # The study's two open knots at their targets (issue: within 0.2); the tighter one
    # needs the larger force and constricts its section more.
    assert abs(loose["lambda_oc"] - 15.0) <= 0.2 and abs(tight["lambda_oc"] - 10.1) <= 0.2
    assert tight["pull_force_N"] > loose["pull_force_N"]
    assert tight["min_area_ratio"] < loose["min_area_ratio"]
    data = json.loads((tmp_path / "summary.json").read_text())
    assert data["knots"]["open_125mm"]["converged"] is True
    # A picture of each knot itself, and what "passed" means (issue 20).
    assert "converged" in data["passed_means"] and "accuracy" in data["passed_means"]
    for name in ("closed_trefoil", "open_185mm", "open_125mm"):
        tube = tmp_path / "figures" / f"tube_{name}.png"
        assert tube.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    # The coarse open knots carry the trade-off study's expected error (README: 0.16 to
    # 0.28 in kappa*D0 at 100 to 200 vertices); the closed one at 100 vertices is fine.
    assert tight["resolution"]["expected_kappa_D0_error"].startswith("0.16 to 0.28")
    assert "fewer than the 400" in loose["resolution"]["warning"]
    assert closed["resolution"]["warning"] is None
    for name in ("closed_profiles.png", "closed_contact_map.png", "open_knots.png"):
        assert (tmp_path / "figures" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rrd = tmp_path / "demo.rrd"
    paths = entity_paths(rrd)
    for entity in ("/closed/rod", "/open_185mm/rod", "/open_125mm/contacts", "/ideal_trefoil"):
        assert any(p.startswith(entity) for p in paths), (entity, paths)
    pts = last_points3d(rrd, "/open_185mm/rod/vertices")
    assert pts.shape == (150, 3) and np.isfinite(pts).all()
    # The open knots' series: end-to-end distance, pulling force, Lambda_OC once in contact.
    # The tightening's and the pull's series apart (issue 20).
    for key in ("end_to_end", "pulling_force", "lambda_oc"):
        assert f"/plots/open_125mm/pull/{key}" in paths, key
    assert "/plots/open_125mm/tighten/pulling_force" in paths
    assert "/plots/open_125mm/pulling_force" not in paths
    # Each knot's rod is logged once per converged load step: those of its tightening and
    # each equilibrium of the force search toward Lambda_OC (the last is the final state).
    closed_steps = steps(rrd, "/closed/rod/vertices", "Points3D:positions")
    assert len(closed_steps) == closed["load_steps"]
    tight_steps = steps(rrd, "/open_125mm/rod/vertices", "Points3D:positions")
    assert len(tight_steps) == tight["load_steps"]
    # The final force of the search is the last logged pulling force (float32 in rerun).
    _, force = scalar_series(rrd, "/plots/open_125mm/pull/pulling_force")
    assert abs(force[-1] - tight["pull_force_N"]) <= 1e-4 * tight["pull_force_N"]
