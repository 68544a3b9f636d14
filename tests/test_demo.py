"""The demo writes its summary, figures and a readable .rrd."""

import json

from tightknot.viz.rrd_read import entity_paths, last_points3d


def test_demo_outputs(tmp_path) -> None:
    from tightknot.demo import run_demo

    summary = run_demo(tmp_path)
    assert summary["passed"]
    # The elastica tip stays within 1e-3 L of solve_bvp at 100 vertices (measured 1.6e-5 L).
    assert summary["elastica_max_tip_error_over_L"] < 1e-3
    assert json.loads((tmp_path / "summary.json").read_text())["converged"] is True
    for name in ("cantilever_convergence.png", "elastica_tip.png"):
        data = (tmp_path / "figures" / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n"
    rrd = tmp_path / "demo.rrd"
    paths = entity_paths(rrd)
    assert any(p.startswith("/rod") for p in paths), paths
    pts = last_points3d(rrd, "/rod/vertices")
    assert pts.shape == (100, 3)
