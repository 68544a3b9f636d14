"""The common exports of micro-CT and knot software read as they are (issue 20): an index
column, semicolons with decimal commas, several header lines, units in the header,
chosen columns, Geomview VECT; and a clear error otherwise."""

import json
from pathlib import Path

import numpy as np
import pytest

from tightknot.app.cli import main
from tightknot.knots import curves
from tightknot.knots.centerline_io import (
    CenterlineError,
    parse_centerline_text,
    parse_columns,
    parse_raw,
)

PTS = [[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [1.5, 1.25, 0.0], [0.0, 1.25, 0.5]]


def _rows(fmt: str, pts=PTS) -> str:
    return "".join(fmt.format(i, *p) for i, p in enumerate(pts, start=1))


def test_index_column_is_dropped() -> None:
    text = _rows("{} {} {} {}\n")
    np.testing.assert_array_equal(parse_centerline_text(text), PTS)


def test_a_first_column_that_is_not_an_index_asks_for_columns() -> None:
    text = "1 0 0 0\n2 1.5 0 0\n5 1.5 1.25 0\n"
    with pytest.raises(CenterlineError, match=r"<text>:3: .*does not count up by 1.*--columns"):
        parse_centerline_text(text)
    with pytest.raises(CenterlineError, match=r"found 5; pick them with --columns"):
        parse_centerline_text("0 0 0 1 2\n1 0 0 1 2\n1 1 0 1 2\n")


def test_semicolons_with_decimal_commas_and_two_header_lines() -> None:
    text = "Centerline of sample 7\nx;y;z\n" + "".join(
        ";".join(repr(v).replace(".", ",") for v in p) + "\n" for p in PTS)
    np.testing.assert_array_equal(parse_centerline_text(text), PTS)
    # Tab-separated with decimal commas too.
    tabbed = "".join("\t".join(repr(v).replace(".", ",") for v in p) + "\n" for p in PTS)
    np.testing.assert_array_equal(parse_centerline_text(tabbed), PTS)


@pytest.mark.parametrize(("header", "unit"), [
    ("x [mm],y [mm],z [mm]", "mm"), ("X (um); Y (um); Z (um)", "um"), ("x_m,y_m,z_m", "m"),
    ("x,y,z", None)])
def test_units_from_the_header(header: str, unit: str | None) -> None:
    delim = ";" if ";" in header else ","
    body = "".join(delim.join(str(v) for v in p) + "\n" for p in PTS)
    raw = parse_raw(header + "\n" + body)
    assert raw.unit == unit
    np.testing.assert_array_equal(raw.values, PTS)


def test_header_names_pick_the_columns_of_a_wider_table() -> None:
    text = "id,label,x [mm],y [mm],z [mm],radius [mm]\n" + "".join(
        f"{i},a,{p[0]},{p[1]},{p[2]},4.2\n" for i, p in enumerate(PTS))
    # "label" is not numeric on the data lines: the error names it.
    with pytest.raises(CenterlineError, match="no line of numbers.*'a'.*--columns"):
        parse_raw(text)
    # ... which --columns leaves out.
    np.testing.assert_array_equal(parse_raw(text, columns=parse_columns("3,4,5")).values, PTS)
    np.testing.assert_array_equal(
        parse_raw(text, columns=parse_columns("x [mm],y [mm],z [mm]")).values, PTS)
    text = text.replace(",a,", ",7,")
    raw = parse_raw(text)
    assert raw.unit == "mm"
    np.testing.assert_array_equal(raw.values, PTS)
    np.testing.assert_array_equal(parse_raw(text, columns=parse_columns("3,4,5")).values, PTS)
    np.testing.assert_array_equal(
        parse_raw(text, columns=parse_columns("X [MM],y [mm],z [mm]")).values, PTS)
    with pytest.raises(CenterlineError, match="--columns 7 but the data has 6 columns"):
        parse_raw(text, columns=parse_columns("1,2,7"))
    with pytest.raises(ValueError, match="--columns '2,3': give three columns"):
        parse_columns("2,3")


def _vect(pts: np.ndarray, closed: bool, four: bool = False) -> str:
    n = len(pts)
    rows = "\n".join(" ".join(repr(v) for v in ([*p, 1.0] if four else p))
                     for p in np.asarray(pts).tolist())
    return (f"{'4VECT' if four else 'VECT'}  # a knot\n1 {n} 1\n{-n if closed else n}\n1\n"
            f"{rows}\n1 0 0 1\n")


def test_geomview_vect_closed_and_homogeneous() -> None:
    knot = curves.trefoil(60)
    raw = parse_raw(_vect(knot, closed=True))
    assert raw.fmt == "vect" and raw.closed is True
    np.testing.assert_array_equal(raw.values, knot)
    four = parse_raw(_vect(knot, closed=False, four=True))
    assert four.closed is None
    np.testing.assert_array_equal(four.values, knot)  # w = 1


@pytest.mark.parametrize(("text", "words"), [
    ("VECT\n2 6 0\n3 3\n0 0\n" + "0 0 0\n" * 6, "holds 2 polylines"),
    ("VECT\n1 4 0\n3\n0\n0 0 0\n1 0 0\n1 1 0\n", "does not match NVertices 4"),
    ("VECT\n1 3 0\n3\n0\n0 0 0\n1 0 0\n", "ends after 2 of its 3 vertices"),
    ("VECT\n1 3 0\nthree\n", "expected an integer"),
    ("KnotPlot 1.0\n\x0c\n", "binary KnotPlot file"),
])
def test_bad_vect_and_knotplot_files(text: str, words: str) -> None:
    with pytest.raises(CenterlineError, match=words):
        parse_raw(text, source="k.vect")


def _analyze(path: Path, *extra: str) -> tuple[int, dict | None]:
    out = path.with_suffix(".json")
    rc = main(["analyze", str(path), "--quiet", "--json", str(out), *extra])
    return rc, json.loads(out.read_text()) if rc == 0 else None


def test_analyze_takes_the_header_unit_and_the_vect_closure(tmp_path: Path, capsys) -> None:
    knot = curves.trefoil(120, size=10.0)  # in mm
    csv = tmp_path / "k.csv"
    csv.write_text("micro-CT export\nindex,x [mm],y [mm],z [mm]\n" + "".join(
        f"{i},{p[0]!r},{p[1]!r},{p[2]!r}\n" for i, p in enumerate(knot.tolist())))
    rc, rep = _analyze(csv, "--diameter", "8.5", "--closed")
    assert rc == 0 and rep["input"]["units_m_per_file_unit"] == 1e-3
    assert "from the file's header" in rep["input"]["units"]
    assert rep["diameter_D0"] == pytest.approx(8.5e-3, rel=1e-15)  # mm, as the file
    # --units that contradicts the header is bad input naming both.
    assert main(["analyze", str(csv), "--diameter", "8.5", "--units", "m", "--quiet"]) == 2
    assert "the header of" in capsys.readouterr().err
    vect = tmp_path / "k.vect"
    vect.write_text(_vect(knot, closed=True))
    rc, rep_v = _analyze(vect, "--diameter", "8.5", "--units", "mm")
    assert rc == 0 and rep_v["closed"] is True  # from the VECT's negative count
    assert rep_v["input"]["closed_source"] == "inferred"
    assert rep_v["L_over_D0"] == pytest.approx(rep["L_over_D0"], rel=1e-12)
    assert main(["analyze", str(vect), "--diameter", "8.5", "--columns", "1,2"]) == 2
    assert "--columns '1,2'" in capsys.readouterr().err


def test_smoothing_an_open_knot_warns_of_its_shorter_ends(tmp_path: Path, capsys) -> None:
    knot = curves.open_trefoil(600, size=0.01)  # noise-free, in metres
    path = tmp_path / "open.csv"
    path.write_text("".join(f"{p[0]!r},{p[1]!r},{p[2]!r}\n" for p in knot.tolist()))
    rc, raw = _analyze(path, "--diameter", "0.008", "--open")
    assert rc == 0 and raw["warnings"] == [] and capsys.readouterr().err == ""
    rc, smooth = _analyze(path, "--diameter", "0.008", "--open", "--smooth", "25")
    assert rc == 0
    (warning,) = smooth["warnings"]
    assert "biased" in warning and "without --smooth" in warning
    assert "warning: --smooth changed the open curve's length" in capsys.readouterr().err
    assert smooth["length_L"] < raw["length_L"]
