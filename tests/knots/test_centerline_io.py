"""Reading and writing user centerlines (tightknot.knots.centerline_io)."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tightknot.knots import curves
from tightknot.knots.centerline_io import (
    CenterlineError,
    parse_centerline_text,
    read_centerline,
    write_centerline_csv,
)


def write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize("name,text", [
    ("a.csv", "x,y,z\n0,0,0\n1,0,0\n1,1,0\n"),
    ("a.tsv", "# comment\n0\t0\t0\n1\t0\t0\n\n1\t1\t0  # trailing\n"),
    ("a.txt", "0 0 0\n1   0 0\n1 1 0\n"),
])
def test_formats(tmp_path, name, text):
    pts = read_centerline(write(tmp_path, name, text), units=1e-3)
    np.testing.assert_allclose(pts, [[0, 0, 0], [1e-3, 0, 0], [1e-3, 1e-3, 0]])


@pytest.mark.parametrize("text,line,words", [
    ("0 0 0\n1 nan 0\n2 0 0\n", 2, "NaN"),
    ("0 0 0\n1 0 inf\n2 0 0\n", 2, "infinite"),
    ("0 0 0\n1 0 0\n", 2, "need at least 3"),
    ("0 0 0\n1 0 0\n1 0 0\n2 0 0\n", 3, "repeats"),
    ("0 0 0\n1 0 0\n2 0 0 4\n", 3, "columns"),
    ("0 0 0\n1 0 zero\n2 0 0\n", 2, "non-numeric"),
    ("x y z\n0 0 0\nfoo bar baz\n2 0 0\n", 3, "non-numeric"),
    ("0 0\n1 0\n2 0\n", 1, "expected 3 columns"),
])
def test_bad_inputs_name_file_and_line(tmp_path, text, line, words):
    path = write(tmp_path, "bad.txt", text)
    with pytest.raises(CenterlineError) as err:
        read_centerline(path)
    msg = str(err.value)
    assert f"{path}:{line}:" in msg and words in msg and "\n" not in msg


def test_open_curve_passed_as_closed(tmp_path):
    pts = curves.open_trefoil(300)
    path = tmp_path / "open.csv"
    write_centerline_csv(path, pts)
    read_centerline(path, closed=False)  # fine as open
    with pytest.raises(CenterlineError, match=r"open\.csv:301: .*looks open"):
        read_centerline(path, closed=True)
    closed = tmp_path / "closed.csv"
    write_centerline_csv(closed, curves.trefoil(200))
    assert read_centerline(closed, closed=True).shape == (200, 3)


def test_round_trip_exact(tmp_path):
    pts = np.random.default_rng(0).normal(size=(50, 3)) * 1e-3
    path = tmp_path / "c.csv"
    write_centerline_csv(path, pts, header="made by a test\nx,y,z")
    np.testing.assert_array_equal(read_centerline(path), pts)  # repr floats: exact
    assert not list(tmp_path.glob(".c.csv.*"))  # no temporary file left behind


def test_repeated_closing_vertex_is_dropped():
    pts = parse_centerline_text("0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 0\n", closed=True)
    assert pts.shape == (4, 3)


number = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr),
                   st.integers(-5, 5).map(str), st.sampled_from(["x", "nan", "1e400", "-", ""]))
line = st.lists(number, min_size=0, max_size=4).flatmap(
    lambda toks: st.sampled_from([",", " ", "\t"]).map(lambda sep: sep.join(toks)))
structured = st.lists(st.one_of(line, st.just("# c"), st.just("")), max_size=12).map("\n".join)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=st.one_of(st.text(max_size=200), structured), closed=st.sampled_from([None, True]))
def test_parser_never_raises_anything_else(text, closed):
    try:
        pts = parse_centerline_text(text, source="h.txt", closed=closed)
    except CenterlineError as exc:
        assert str(exc).startswith("h.txt:")
    else:
        assert pts.ndim == 2 and pts.shape[1] == 3 and pts.shape[0] >= 3
        assert np.all(np.isfinite(pts))
