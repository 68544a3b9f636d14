"""``tightknot tie --start FILE``: a user's own start curve, closed or open, any knot type."""

import json
from pathlib import Path

import numpy as np
import pytest

from tightknot.app.cli import main
from tightknot.knots import curves, families
from tightknot.knots.open_measures import lambda_oc

D0_MM = 8.5


def _loose(points: np.ndarray, closed: bool, margin: float = 1.3) -> np.ndarray:
    """``points`` scaled [mm] so that their closest non-local strands are ``margin`` D0
    apart: a loose knot as a user would trace it."""
    d, _, _ = curves.min_nonlocal_distance(points, closed, curves.exclusion_arc_length(1.0))
    return points * margin * D0_MM / d


def _write_mm(path: Path, points: np.ndarray) -> Path:
    np.savetxt(path, points, delimiter=",", header="x [mm],y [mm],z [mm]", comments="")
    return path


# Coarse rods with a loose Newton tolerance throughout: the CLI path and the topology
# bookkeeping, not the physics (the built-in knots' tests judge that).
FAST = ["--residual-tol", "1e-3", "--quiet"]


@pytest.mark.parametrize("name,curve,nodes", [
    ("5_1", families.torus_knot(2, 5, 400), 80),
    ("5_2", families.twist_knot(3, 600), 100),
])
def test_closed_start_curve_is_tied_and_keeps_its_type(name, curve, nodes,
                                                      tmp_path: Path) -> None:
    start = _write_mm(tmp_path / f"{name}.csv", _loose(curve, True))
    out = tmp_path / "run"
    assert main(["tie", "--start", str(start), "--closed", "--l0-over-d0", "40",
                 "--nodes", str(nodes), "--tighten-steps", "10", "--out", str(out),
                 *FAST]) == 0
    summary = json.loads((out / "summary.json").read_text())
    # converged: every load step's type was checked against the detected one.
    assert summary["converged"] and summary["knot_type"] == name
    assert summary["scene"] == "closed_start"
    assert summary["rest_length_m"] == pytest.approx(40 * D0_MM * 1e-3, rel=1e-12)
    start_info = summary["start_curve"]
    assert start_info["file"] == str(start) and "mm" in start_info["units"]
    assert start_info["start_length_over_L0"] > 1.0  # it was shrunk to L0
    config = json.loads((out / "config.json").read_text())
    assert config["start"] == str(start) and config["knot_type"] == name
    assert out.name == "run"


def test_start_config_reads_back(tmp_path: Path) -> None:
    from tightknot.app.config import config_from_dict

    start = _write_mm(tmp_path / "k.csv", _loose(families.torus_knot(2, 5, 400), True))
    cfg = config_from_dict({"knot": "closed", "start": str(start)})
    # Default L0: 5 % above the 5_1's ideal length, rounded up to 0.1 D0, as the built-ins.
    from tightknot.knots.scenes import default_l0_over_d0

    assert cfg.l0_over_d0 == pytest.approx(default_l0_over_d0("5_1"))
    assert cfg.knot_type == "5_1" and cfg.twist is True
    assert config_from_dict(cfg.to_dict()) == cfg  # a run folder's config.json reruns it
    assert cfg.scene_name == "closed_start_5_1"


def test_torus_knot_t34_is_named_8_19(tmp_path: Path) -> None:
    from tightknot.app.config import config_from_dict

    start = _write_mm(tmp_path / "t34.csv", _loose(families.torus_knot(3, 4, 600), True))
    cfg = config_from_dict({"knot": "closed", "start": str(start), "l0_over_d0": 40.0})
    assert cfg.knot_type == "8_19"


def test_open_start_figure_eight_is_tightened_by_a_force(tmp_path: Path) -> None:
    pts = _loose(curves.open_figure_eight(300, 1.0, 1.5), False)
    start = tmp_path / "overhand8.txt"
    np.savetxt(start, pts)  # no header: --units says mm
    out = tmp_path / "run"
    assert main(["tie", "--start", str(start), "--units", "mm", "--open", "--force", "1",
                 "--nodes", "120", "--pull-steps", "4", "--tighten-steps", "2",
                 "--out", str(out), *FAST]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] and summary["knot_type"] == "4_1"
    assert summary["pull_force_N"] == pytest.approx(1.0)
    # Tightened: the knot's length in contact is shorter than the start's (where its
    # strands are 1.3 D0 apart, a contact tolerance of 0.35 counts them as touching).
    loose = lambda_oc(pts * 1e-3, D0_MM * 1e-3, np.full(len(pts), 0.5 * D0_MM * 1e-3),
                      tol=0.35)
    assert summary["lambda_oc"] < loose


def _error(argv: list[str], capsys) -> str:
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    return err[0]


def test_start_bad_input_is_one_line_naming_the_file(tmp_path: Path, capsys) -> None:
    start = _write_mm(tmp_path / "k.csv", _loose(families.torus_knot(2, 5, 400), True))
    out = tmp_path / "r"
    base = ["tie", "--start", str(start), "--closed", "--out", str(out)]
    err = _error([*base, "--knot", "5_2"], capsys)
    assert str(start) in err and "5_1" in err and "5_2" in err
    # A rod 3.5 times thicker than the curve's spacing allows: it intersects itself.
    err = _error([*base, "--diameter", "0.03"], capsys)
    assert str(start) in err and "intersects itself: vertices" in err
    err = _error([*base, "--l0-over-d0", "500"], capsys)
    assert str(start) in err and "longer than the start curve" in err
    err = _error(["tie", "--start", str(start), "--open", "--force", "1", "--out", str(out)],
                 capsys)
    assert "looks closed" in err
    err = _error(["tie", "--start", str(tmp_path / "none.csv"), "--closed", "--out", str(out)],
                 capsys)
    assert "none.csv" in err and "cannot read" in err
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,z\n1,2,3\n1,2,oops\n")
    err = _error(["tie", "--start", str(bad), "--closed", "--out", str(out)], capsys)
    assert "bad.csv" in err
    err = _error(["tie", "closed", "--units", "mm", "--out", str(out)], capsys)
    assert "units" in err
    assert not out.exists()


def test_intersecting_curve_names_its_vertices() -> None:
    from tightknot.knots.start_curve import (
        StartCurve,
        StartCurveError,
        check_no_intersection,
        closest_pair,
    )

    pts = _loose(families.torus_knot(2, 5, 400), True) * 1e-3  # strands 11 mm apart
    curve = StartCurve("k.csv", pts, True, "m")
    d, i, j = closest_pair(pts, True, 0.02)
    with pytest.raises(StartCurveError, match=f"k.csv: .* vertices {i} and {j} "):
        check_no_intersection(curve, 0.02)
    # The vertices named are the closest pair's, to within the sag of an edge.
    assert np.linalg.norm(pts[i] - pts[j]) == pytest.approx(d, rel=0.05)
    # Slightly closer than the 2 % margin: grown to it, not refused.
    assert check_no_intersection(curve, 1.01 * d / 1.02) == pytest.approx(1.01)


def test_ideal_start_shape_ties_and_reports_fitting_measures(tmp_path: Path,
                                                             monkeypatch) -> None:
    from tightknot.viz import figures

    titles: list[str] = []
    real = figures.plot_closed_profiles

    def spy(report, path, ideal=None, label="knot", knot="closed trefoil"):
        titles.append(knot)
        assert ideal is not None and ideal["aligned"] is not None  # the ideal 4_1, placed
        return real(report, path, ideal=ideal, label=label, knot=knot)

    monkeypatch.setattr(figures, "plot_closed_profiles", spy)
    out = tmp_path / "run"
    assert main(["tie", "closed", "--knot", "4_1", "--start-shape", "ideal", "--nodes", "100",
                 "--out", str(out), *FAST]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] and summary["knot_type"] == "4_1"
    # No trefoil's 3-fold axis: null with the reason, not a misleading number.
    assert summary["rho"] is None and summary["z"] is None
    assert not summary["threefold"]["applied"] and "4_1" in summary["threefold"]["reason"]
    assert summary["ideal"]["L_over_D"] == pytest.approx(21.0483)
    assert "measured" in summary["ideal"]["source"] and summary["ideal"]["shape_shipped"]
    assert titles == ["closed figure-eight 4_1"]
    assert json.loads((out / "config.json").read_text())["start_shape"] == "ideal"


@pytest.mark.parametrize("argv,message", [
    (["tie", "closed", "--knot", "5_2", "--start-shape", "ideal"], "start_shape ideal"),
    (["tie", "open", "--knot", "5_1", "--force", "1", "--start-shape", "ideal"],
     "start_shape ideal"),
])
def test_ideal_start_shape_bad_input(argv, message, tmp_path: Path, capsys) -> None:
    err = _error([*argv, "--out", str(tmp_path / "r")], capsys)
    assert message in err and "3_1, 4_1, 5_1, 6_1, 8_19" in err
