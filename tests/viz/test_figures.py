"""Figures are written as complete PNG files, atomically."""

import numpy as np

from tightknot.knots import curves
from tightknot.knots.ideal import load_ideal_trefoil
from tightknot.knots.measure import analyze_centerline
from tightknot.viz.figures import plot_closed_profiles, plot_contact_map, plot_open_knots

PNG = b"\x89PNG\r\n\x1a\n"


def test_figures(tmp_path):
    ideal = analyze_centerline(load_ideal_trefoil(1.0)[::4], 1.0, True, contact_tol=0.002)
    knot = analyze_centerline(curves.scale_for_diameter(curves.trefoil(300), 1.0, True), 1.0,
                              True, contact_tol=0.05)
    plot_closed_profiles(knot, tmp_path / "profiles.png", ideal=ideal)
    plot_contact_map(knot, tmp_path / "contact.png", ideal=ideal)
    opens = {}
    for lab, clearance in (("looser", 1.3), ("tighter", 1.0)):
        pts = curves.scale_for_diameter(curves.open_trefoil(400), 1.0, False, clearance)
        opens[lab] = analyze_centerline(pts, 1.0, False, contact_tol=0.1)
    lc = {k: np.zeros(len(r["s"])) for k, r in opens.items()}
    area = {k: np.ones(len(r["s"])) for k, r in opens.items()}
    press = {k: np.linspace(0.0, 0.9, len(r["s"])) for k, r in opens.items()}
    plot_open_knots(opens, tmp_path / "open.png", contact_width=lc, area_ratio=area,
                    pressure=press, judged_area_ratio=0.66)
    for name in ("profiles.png", "contact.png", "open.png"):
        data = (tmp_path / name).read_bytes()
        assert data.startswith(PNG) and data.rstrip().endswith(b"IEND\xaeB`\x82")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["contact.png", "open.png",
                                                          "profiles.png"]
