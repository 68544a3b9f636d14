"""``tightknot analyze``: the study's measurements on a centerline file (issue 5).

cli.py does not call :func:`tightknot.app.analyze.register` yet, so the tests build their own
parser with it and run the handler, as ``tightknot.app.cli.main`` will.
"""

import argparse
import contextlib
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest

from tightknot.app.analyze import (
    CLOSED_PROFILES_PNG,
    CONTACT_MAP_PNG,
    OPEN_KNOT_PNG,
    json_safe,
    parse_units,
    register,
)
from tightknot.knots import curves
from tightknot.knots.centerline_io import write_centerline_csv
from tightknot.knots.curves import exclusion_arc_length, min_nonlocal_distance
from tightknot.knots.ideal import IDEAL_TREFOIL_FILE
from tightknot.knots.measure import analyze_centerline

IDEAL_PATH = Path(__file__).resolve().parents[2] / "tightknot" / "knots" / "data" \
    / IDEAL_TREFOIL_FILE
PNG = b"\x89PNG\r\n\x1a\n"
D0_MM = 8.5


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="tightknot")
    register(p.add_subparsers(dest="command"))
    return p


def run(*argv: str) -> tuple[int, str, str]:
    """Parse ``analyze ARGV`` and run the handler; returns (exit code, stdout, stderr)."""
    args = parser().parse_args(["analyze", *map(str, argv)])
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = args.handler(args)
    return code, out.getvalue(), err.getvalue()


def strict_json(path):
    def refuse(token):
        raise AssertionError(f"{token} in JSON")

    return json.loads(path.read_text(), parse_constant=refuse)


@pytest.fixture(scope="module")
def ideal_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ideal")
    code, out, err = run(IDEAL_PATH, "--diameter", "1.0", "--closed",
                         "--json", folder / "ideal.json", "--figures", folder / "figs")
    return code, out, err, folder


def test_ideal_trefoil_file(ideal_run):
    code, out, err, folder = ideal_run
    assert code == 0 and err == ""
    rep = strict_json(folder / "ideal.json")
    # The file's tube diameter 2r (Rawdon's polygonal thickness) is 0.99998 in its own units,
    # so D0 = 1.0 is the tube diameter and, without --rest-length, D = D0: L/D = L = 16.3715,
    # the Ridgerunner ropelength 32.7436 / 2 = 16.3718 to 2e-5 relative (the 2e-5 of 2r - 1).
    assert rep["L_over_D"] == pytest.approx(16.372, abs=0.003)
    # The raw polygon reaches the ideal tube's active limit kappa*D = 2 (data README: 2.000).
    assert rep["kappa_D0_max"] == pytest.approx(2.00, abs=0.02)
    assert rep["n_curvature_spikes"] == 6
    assert rep["knot_type"] == "3_1" and rep["knot_determinant"] == 3
    # Double contact at every vertex (within 0.5 % of D), as the data README states.
    assert rep["double_contact_fraction"] == 1.0
    assert rep["closed"] is True and rep["smoothed"] is False
    assert rep["input"]["closed_source"] == "option"
    for line in ("3_1", "16.37", "max 2.000", "curvature spikes   6", "double contact"):
        assert line in out


def test_ideal_json_keys(ideal_run):
    rep = strict_json(ideal_run[3] / "ideal.json")
    expected = {"closed", "diameter_D0", "n_points", "length_L", "stretch_L_over_L0",
                "L_over_D", "L_over_D0", "S", "s", "kappa_D0", "kappa_D0_sorted",
                "kappa_D0_max", "kappa_D0_min", "knot_type", "alexander_polynomial",
                "contact_s", "contact_sigma", "curvature_spikes", "n_curvature_spikes",
                "rho", "z", "inner_segments_s", "outer_segments_s", "double_contact_fraction",
                "min_nonlocal_distance_over_D0", "input"}
    assert expected <= set(rep)
    assert rep["n_points"] == 2400 and len(rep["kappa_D0"]) == len(rep["rho"]) == 2400
    assert len(rep["contact_s"]) == len(rep["contact_sigma"]) > 0


def test_ideal_figures(ideal_run):
    figs = ideal_run[3] / "figs"
    assert sorted(p.name for p in figs.iterdir()) == sorted([CLOSED_PROFILES_PNG,
                                                              CONTACT_MAP_PNG])
    for p in figs.iterdir():
        data = p.read_bytes()
        assert data.startswith(PNG) and data.rstrip().endswith(b"IEND\xaeB`\x82")
        assert p.stat().st_mode & 0o044  # not left 0600 by the temporary file
    assert f"wrote {figs / CLOSED_PROFILES_PNG}" in ideal_run[1]


def _trefoil_m() -> np.ndarray:
    """A loose closed trefoil [m] for a rod of D0 = 8.5 mm, 300 vertices (fast to measure)."""
    return curves.scale_for_diameter(curves.trefoil(300), D0_MM * 1e-3, True, 1.2)


def _open_trefoil_m() -> np.ndarray:
    """An open trefoil [m] whose closest non-local pair is 0.995 D0 apart (so it has contact).

    Scaling changes which pairs count as non-local (the window is pi D0 / 2 of arc length),
    so the scale is found by fixed-point iteration; it settles within a few steps.
    """
    d0 = D0_MM * 1e-3
    q = curves.open_trefoil(300)
    for _ in range(12):
        dmin, _, _ = min_nonlocal_distance(q, False, exclusion_arc_length(d0))
        q = q * (0.995 * d0 / dmin)
    return q


def _assert_same(got: dict, want: dict, rtol: float) -> None:
    """Every measurement of ``want`` equals ``got`` (scalars and arrays, to ``rtol``)."""
    want = json_safe(want)
    for key, value in want.items():
        if isinstance(value, float):
            assert got[key] == pytest.approx(value, rel=rtol, abs=1e-12), key
        elif isinstance(value, list) and value and isinstance(value[0], float):
            np.testing.assert_allclose(got[key], value, rtol=rtol, atol=1e-12, err_msg=key)
        elif key not in ("curvature_spikes",):
            assert got[key] == value, key
    assert len(got["curvature_spikes"]) == len(want["curvature_spikes"])


@pytest.mark.parametrize("smooth", [None, 25.0])
def test_round_trip_closed_in_mm(tmp_path, smooth):
    # A centerline in metres, written in mm as an experimentalist would, analysed with
    # --units mm: the same measurements as analyze_centerline on the array itself.
    pts = _trefoil_m()
    l0 = 0.98 * float(np.sum(np.linalg.norm(np.roll(pts, -1, 0) - pts, axis=1)))
    path = tmp_path / "knot.csv"
    write_centerline_csv(path, pts * 1e3)
    argv = [path, "--units", "mm", "--diameter", D0_MM, "--rest-length", l0 * 1e3,
            "--poisson", "0.5", "--json", tmp_path / "knot.json", "--quiet"]
    if smooth is not None:
        argv += ["--smooth", smooth]
    code, out, err = run(*argv)
    assert (code, out, err) == (0, "", "")
    got = strict_json(tmp_path / "knot.json")
    want = analyze_centerline(pts, D0_MM * 1e-3, True, smooth_n_gauss=smooth, rest_length=l0)
    # mm -> m rescaling rounds in the last bits only.
    _assert_same(got, want, rtol=1e-9)
    assert got["input"] == {"file": str(path), "units_m_per_file_unit": 1e-3,
                            "units": "mm (--units)", "closed_source": "inferred"}
    # Stretch of the measured curve; the Gaussian average shortens it (cuts the bends).
    assert got["stretch_L_over_L0"] == pytest.approx(got["length_L"] / l0, rel=1e-12)
    if smooth is None:
        assert got["stretch_L_over_L0"] == pytest.approx(1 / 0.98, rel=1e-9)
    else:
        assert got["length_L"] < got["length_before_smoothing"]


def test_round_trip_open_exact(tmp_path):
    pts = _open_trefoil_m()
    path = tmp_path / "open.csv"
    write_centerline_csv(path, pts)  # repr floats: the read-back array is bit-identical
    code, out, err = run(path, "--diameter", D0_MM * 1e-3, "--json", tmp_path / "o.json",
                         "--figures", tmp_path / "figs")
    assert code == 0 and err == ""
    assert "open (inferred from the file ends)" in out and "Lambda_OC" in out
    got = strict_json(tmp_path / "o.json")
    _assert_same(got, analyze_centerline(pts, D0_MM * 1e-3, False), rtol=0.0)
    assert got["knot_type"] == "3_1" and got["Lambda_OC"] > 0
    assert f"Lambda_OC          {got['Lambda_OC']:.3f}" in out
    assert [p.name for p in (tmp_path / "figs").iterdir()] == [OPEN_KNOT_PNG]


@pytest.mark.parametrize("repeat_first", [False, True])
def test_closed_inferred(tmp_path, repeat_first):
    pts = _trefoil_m()
    if repeat_first:
        pts = np.vstack([pts, pts[:1]])  # closed files often repeat the first vertex
    path = tmp_path / "k.txt"
    path.write_text("\n".join(" ".join(f"{v:.17g}" for v in row) for row in pts) + "\n")
    code, out, err = run(path, "--diameter", D0_MM * 1e-3)
    assert code == 0 and err == ""
    assert "300 points, closed (inferred from the file ends)" in out


def test_quiet_prints_nothing(tmp_path):
    path = tmp_path / "k.csv"
    write_centerline_csv(path, _trefoil_m())
    assert run(path, "--diameter", D0_MM * 1e-3, "--quiet") == (0, "", "")


# -- bad input: exit code 2 and one line naming the file and line ----------------------------
@pytest.mark.parametrize("text,line,words", [
    ("0 0 0\n1 nan 0\n2 0 0\n3 1 0\n", 2, "NaN"),
    ("x,y,z\n0,0,0\n1,0,0\n", 3, "need at least 3"),
    ("0 0 0\n1 0 0\n1 0 0\n2 0 0\n", 3, "repeats"),
    ("0 0 0\n1 0 0\n2 0 0 4\n3 1 0\n", 3, "columns"),
    ("0 0 0\n1 0 zero\n2 0 0\n", 2, "non-numeric"),
])
def test_bad_file(tmp_path, text, line, words):
    path = tmp_path / "bad.txt"
    path.write_text(text)
    code, out, err = run(path, "--diameter", "1")
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and f"{path}:{line}:" in err and words in err


def test_open_curve_passed_as_closed(tmp_path):
    path = tmp_path / "open.csv"
    write_centerline_csv(path, _open_trefoil_m())  # header on line 1, 300 vertices
    code, out, err = run(path, "--diameter", D0_MM * 1e-3, "--closed")
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and f"{path}:301:" in err and "looks open" in err


def test_missing_file(tmp_path):
    code, _, err = run(tmp_path / "nope.csv", "--diameter", "1")
    assert code == 2 and err.count("\n") == 1 and "nope.csv" in err


@pytest.mark.parametrize("option", ["--json", "--figures"])
def test_missing_output_folder_checked_first(tmp_path, option):
    # The input does not exist either: the output is refused before any reading.
    target = tmp_path / "no_such_folder" / "out"
    code, out, err = run(tmp_path / "nope.csv", "--diameter", "1", option, target)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and option in err and "no_such_folder" in err
    assert not (tmp_path / "no_such_folder").exists()


def test_json_path_is_a_folder(tmp_path):
    code, _, err = run(IDEAL_PATH, "--diameter", "1", "--json", tmp_path)
    assert code == 2 and "is a folder" in err


def test_figures_not_created_on_bad_input(tmp_path):
    path = tmp_path / "bad.txt"
    path.write_text("0 0 0\n1 nan 0\n2 0 0\n")
    code, _, _ = run(path, "--diameter", "1", "--figures", tmp_path / "figs")
    assert code == 2 and not (tmp_path / "figs").exists()


@pytest.mark.parametrize("argv,words", [
    (["--diameter", "0"], "--diameter"),
    (["--diameter", "-1"], "--diameter"),
    (["--diameter", "nan"], "--diameter"),
    (["--diameter", "1", "--closed", "--open"], "exclusive"),
    (["--diameter", "1", "--units", "furlong"], "--units"),
    (["--diameter", "1", "--units", "-2"], "--units"),
    (["--diameter", "1", "--rest-length", "0"], "--rest-length"),
    (["--diameter", "1", "--smooth", "0"], "--smooth"),
    (["--diameter", "1", "--poisson", "0.7"], "--poisson"),
])
def test_bad_option(argv, words):
    code, out, err = run(IDEAL_PATH, *argv)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and words in err


def test_rest_length_in_wrong_units(tmp_path):
    path = tmp_path / "k.csv"
    write_centerline_csv(path, _trefoil_m() * 1e3)
    # L0 given in metres while the file is in mm: L/L0 ~ 1000, so D = D0[1 - nu(L-L0)/L0] < 0.
    code, _, err = run(path, "--units", "mm", "--diameter", "8.5", "--rest-length", "0.139")
    assert code == 2 and err.count("\n") == 1 and "reduced diameter" in err


# -- helpers ---------------------------------------------------------------------------------
def test_units():
    assert parse_units("mm") == 1e-3 and parse_units("um") == 1e-6 and parse_units("m") == 1.0
    assert parse_units("2.5e-4") == 2.5e-4


def test_json_safe():
    got = json_safe({"a": float("nan"), "b": np.array([1.0, np.inf]), "c": (np.int64(3),),
                     "d": np.float32(0.5), "e": None, "f": np.bool_(True)})
    assert got == {"a": None, "b": [1.0, None], "c": [3], "d": 0.5, "e": None, "f": True}
    json.dumps(got, allow_nan=False)
    assert math.isfinite(got["d"])


def test_help_has_examples():
    sub = parser()._subparsers._group_actions[0].choices["analyze"]
    text = sub.format_help()
    assert "examples:" in text and "--units mm --diameter 8.5" in text
